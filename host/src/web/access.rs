//! Who may do what with the web view.
//!
//! Listening on a loopback address, the page is open: whoever can reach it is
//! on this computer. On any other address, controlling the machine needs the
//! token printed at start (in a URL and a QR code); without it a browser may
//! only watch, or gets nothing at all with `--private`.
//!
//! Independently of the token, two checks keep other web sites out. A request
//! is answered only when its `Host` names this server: an IP literal (the
//! listen address, any loopback literal for a loopback listen, any literal
//! for an unspecified listen), `localhost` for a loopback listen, or a name
//! given with `--allow-host`. A DNS-rebinding page (evil.example resolving to
//! 127.0.0.1) sends `Host: evil.example` and is refused. And a websocket is
//! refused when the page that opens it comes from another origin (browsers
//! let any site open websockets to 127.0.0.1; the Origin header they always
//! send tells them apart).

use std::net::IpAddr;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    /// May take control (one browser controls at a time).
    Control,
    /// Sees everything, sends nothing.
    Watch,
}

#[derive(Clone, Debug)]
pub struct Access {
    /// None: no token needed (loopback).
    token: Option<String>,
    private: bool,
    listen: IpAddr,
    /// Host names given with `--allow-host`, lower case.
    names: Vec<String>,
}

impl Access {
    /// The policy for a server listening on `ip`, also answering to `names`.
    pub fn new(ip: IpAddr, private: bool, names: &[String]) -> Access {
        Access {
            token: (!ip.is_loopback()).then(new_token),
            private,
            listen: ip,
            names: names.iter().map(|n| n.to_ascii_lowercase()).collect(),
        }
    }

    /// The token, when one is needed.
    pub fn token(&self) -> Option<&str> {
        self.token.as_deref()
    }

    /// The role of a request that presented `token` (None: nothing may be seen).
    pub fn role(&self, token: Option<&str>) -> Option<Role> {
        match &self.token {
            None => Some(Role::Control),
            Some(t) if token.is_some_and(|g| same(g.as_bytes(), t.as_bytes())) => {
                Some(Role::Control)
            }
            Some(_) if self.private => None,
            Some(_) => Some(Role::Watch),
        }
    }

    /// Whether a request's `Host` header names this server (the port is not
    /// compared: a rebinding page uses the same port anyway, and a proxy may
    /// change it).
    pub fn host_allowed(&self, host: Option<&str>) -> bool {
        let Some(name) = host.and_then(host_name) else {
            return false;
        };
        if let Some(ip) = ip_literal(&name) {
            return if self.listen.is_unspecified() {
                true
            } else if self.listen.is_loopback() {
                ip.is_loopback()
            } else {
                ip == self.listen
            };
        }
        (self.listen.is_loopback() && name == "localhost") || self.names.contains(&name)
    }

    /// A websocket may be opened by the page itself only: its Origin (when
    /// the client sends one, as browsers do) must be `http(s)://` and the host
    /// the request went to, which must itself be allowed.
    pub fn origin_allowed(&self, origin: Option<&str>, host: Option<&str>) -> bool {
        if !self.host_allowed(host) {
            return false;
        }
        match (origin, host) {
            (None, _) => true,
            (Some(o), Some(h)) => {
                let o = o
                    .strip_prefix("http://")
                    .or_else(|| o.strip_prefix("https://"));
                o.is_some_and(|o| o.trim_end_matches('/').eq_ignore_ascii_case(h))
            }
            (Some(_), None) => false,
        }
    }
}

/// The name part of a Host header, lower case: `[::1]:80` -> `::1`,
/// `Example.org:8080` -> `example.org`. None when it is malformed.
fn host_name(host: &str) -> Option<String> {
    let host = host.trim();
    let name = if let Some(rest) = host.strip_prefix('[') {
        let (inside, after) = rest.split_once(']')?;
        if !(after.is_empty() || after.strip_prefix(':').is_some_and(is_port)) {
            return None;
        }
        inside
    } else {
        match host.rsplit_once(':') {
            Some((n, p)) if is_port(p) => n,
            Some(_) => return None,
            None => host,
        }
    };
    let name = name.trim_end_matches('.');
    (!name.is_empty()).then(|| name.to_ascii_lowercase())
}

fn is_port(p: &str) -> bool {
    !p.is_empty() && p.len() <= 5 && p.bytes().all(|b| b.is_ascii_digit())
}

/// An IP address written out (not a name that might resolve to one).
fn ip_literal(name: &str) -> Option<IpAddr> {
    name.parse().ok()
}

/// 128 random bits as hex.
fn new_token() -> String {
    let mut b = [0u8; 16];
    // Without a random source there is no safe token: refuse to run.
    getrandom::fill(&mut b).expect("the operating system's random source");
    b.iter().map(|x| format!("{x:02x}")).collect()
}

/// Compares in time independent of where the first difference is.
fn same(a: &[u8], b: &[u8]) -> bool {
    a.len() == b.len() && a.iter().zip(b).fold(0u8, |acc, (x, y)| acc | (x ^ y)) == 0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn loopback_is_open_elsewhere_the_token_controls() {
        let open = Access::new("127.0.0.1".parse().unwrap(), true, &[]);
        assert_eq!(open.token(), None);
        assert_eq!(open.role(None), Some(Role::Control));
        let lan = Access::new("0.0.0.0".parse().unwrap(), false, &[]);
        let t = lan.token().unwrap().to_string();
        assert_eq!(t.len(), 32);
        assert_eq!(lan.role(Some(&t)), Some(Role::Control));
        assert_eq!(lan.role(None), Some(Role::Watch));
        assert_eq!(lan.role(Some("0123")), Some(Role::Watch));
        let private = Access::new("192.168.1.5".parse().unwrap(), true, &[]);
        assert_eq!(private.role(None), None);
        assert_eq!(
            private.role(Some(private.token().unwrap())),
            Some(Role::Control)
        );
        assert_ne!(private.token(), lan.token());
    }

    #[test]
    fn only_requests_naming_this_server() {
        let lo = Access::new("127.0.0.1".parse().unwrap(), false, &[]);
        for ok in [
            "127.0.0.1:8080",
            "localhost:8080",
            "LocalHost",
            "[::1]:8080",
            "127.0.0.2",
        ] {
            assert!(lo.host_allowed(Some(ok)), "{ok}");
        }
        for bad in [
            "evil.example:8080",
            "evil.example",
            "localhost.evil.example",
            "192.168.1.5:8080",
            "127.0.0.1:8080:1",
            "[::1]x",
            "",
            ":8080",
        ] {
            assert!(!lo.host_allowed(Some(bad)), "{bad}");
        }
        assert!(!lo.host_allowed(None));
        let lan = Access::new(
            "192.168.1.5".parse().unwrap(),
            false,
            &["Plotter.local".into()],
        );
        assert!(lan.host_allowed(Some("192.168.1.5:8080")));
        assert!(lan.host_allowed(Some("plotter.local:8080")));
        assert!(!lan.host_allowed(Some("localhost:8080")));
        assert!(!lan.host_allowed(Some("10.0.0.1:8080")));
        assert!(!lan.host_allowed(Some("evil.example:8080")));
        let any = Access::new("0.0.0.0".parse().unwrap(), false, &[]);
        assert!(any.host_allowed(Some("10.0.0.7:8080")));
        assert!(!any.host_allowed(Some("evil.example:8080")));
    }

    #[test]
    fn websockets_only_from_the_page_itself() {
        let lo = Access::new("127.0.0.1".parse().unwrap(), false, &[]);
        assert!(lo.origin_allowed(None, Some("127.0.0.1:8080")));
        assert!(lo.origin_allowed(Some("http://127.0.0.1:8080"), Some("127.0.0.1:8080")));
        assert!(!lo.origin_allowed(Some("http://evil.example"), Some("127.0.0.1:8080")));
        assert!(!lo.origin_allowed(Some("null"), Some("127.0.0.1:8080")));
        // Rebinding: Origin and Host agree, but name another site.
        assert!(!lo.origin_allowed(Some("http://evil.example:8080"), Some("evil.example:8080")));
        // Another port on this computer is another origin.
        assert!(!lo.origin_allowed(Some("http://127.0.0.1:9999"), Some("127.0.0.1:8080")));
    }
}
