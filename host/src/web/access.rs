//! Who may do what with the web view.
//!
//! Listening on a loopback address, the page is open: whoever can reach it is
//! on this computer. On any other address, controlling the machine needs the
//! token printed at start (in a URL and a QR code); without it a browser may
//! only watch, or gets nothing at all with `--private`. Independently, a
//! websocket is refused when the page that opens it comes from another origin
//! (browsers let any site open websockets to 127.0.0.1; the Origin header
//! they always send tells them apart).

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
}

impl Access {
    /// The policy for a server listening on `ip`.
    pub fn new(ip: IpAddr, private: bool) -> Access {
        Access {
            token: (!ip.is_loopback()).then(new_token),
            private,
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

/// A websocket may be opened by the page itself only: its Origin (when the
/// client sends one, as browsers do) must name the host the request went to.
pub fn same_origin(origin: Option<&str>, host: Option<&str>) -> bool {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn loopback_is_open_elsewhere_the_token_controls() {
        let open = Access::new("127.0.0.1".parse().unwrap(), true);
        assert_eq!(open.token(), None);
        assert_eq!(open.role(None), Some(Role::Control));
        let lan = Access::new("0.0.0.0".parse().unwrap(), false);
        let t = lan.token().unwrap().to_string();
        assert_eq!(t.len(), 32);
        assert_eq!(lan.role(Some(&t)), Some(Role::Control));
        assert_eq!(lan.role(None), Some(Role::Watch));
        assert_eq!(lan.role(Some("0123")), Some(Role::Watch));
        let private = Access::new("192.168.1.5".parse().unwrap(), true);
        assert_eq!(private.role(None), None);
        assert_eq!(
            private.role(Some(private.token().unwrap())),
            Some(Role::Control)
        );
        assert_ne!(private.token(), lan.token());
    }

    #[test]
    fn websockets_only_from_the_page_itself() {
        assert!(same_origin(None, Some("127.0.0.1:8080")));
        assert!(same_origin(
            Some("http://127.0.0.1:8080"),
            Some("127.0.0.1:8080")
        ));
        assert!(!same_origin(
            Some("http://evil.example"),
            Some("127.0.0.1:8080")
        ));
        assert!(!same_origin(Some("null"), Some("127.0.0.1:8080")));
    }
}
