//! inkstep's set-up: what `cargo setup`, `cargo test-host` and `cargo emu` run first.
//!
//! The tests and the emulator need four things a machine with only Rust lacks: the
//! firmware's target (thumbv7m-none-eabi), its linker (flip-link), and for the
//! emulator's CPU (unicorn, built from C by its crate) cmake and libclang. This program
//! finds each one or installs it, then runs the command it was asked for with an
//! environment in which the builds find them, so that a missing tool is named in one
//! line here and never fails deep inside a build script.
//!
//! Where things come from, in order:
//! - the target: `rustup target add` (into the toolchain rustup manages for this user);
//! - flip-link: `PATH` or `$CARGO_HOME/bin`, else `cargo install` into `$CARGO_HOME/bin`;
//! - cmake and libclang: what the system has (`PATH`; the directories clang-sys
//!   searches), else Debian's packages when it runs as root, else pinned PyPI wheels in
//!   `.tools/` inside the project (no root needed). `--user` (or `INKSTEP_SETUP=user`)
//!   skips the system: only what this user has, and the wheels. (`INKSTEP_TOOLS`
//!   names another folder than `.tools/`.)
//!
//! It never upgrades or removes what is there. When everything is found it does nothing
//! but look (a few milliseconds). It uses the standard library only, because it has to
//! build before anything it installs exists.

use std::env;
use std::ffi::{OsStr, OsString};
use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode, Stdio};

/// The firmware's target.
const TARGET: &str = "thumbv7m-none-eabi";
/// The firmware's linker, pinned so that every machine links the same way.
const FLIP_LINK: &str = "flip-link@0.1.12";
/// The PyPI wheels used without root. cmake stays on 3.x: unicorn's CMakeLists asks for
/// a minimum version that cmake 4 no longer accepts.
const CMAKE_WHEEL: &str = "cmake==3.31.6";
const LIBCLANG_WHEEL: &str = "libclang==18.1.1";
/// Rustup components the checks (not the tests) use: `cargo setup --dev`.
const DEV_COMPONENTS: [&str; 2] = ["rustfmt", "clippy"];

fn main() -> ExitCode {
    let mut args: Vec<OsString> = env::args_os().skip(1).collect();
    let command = args.first().and_then(|a| a.to_str()).map(str::to_owned);
    let mut opts = Options {
        user_only: env::var("INKSTEP_SETUP").is_ok_and(|v| v == "user"),
        dev: false,
        quiet: true,
    };
    let result = match command.as_deref() {
        Some("test") => {
            args.remove(0);
            setup(&opts).and_then(|found| run_cargo(&found, &test_args(&args)))
        }
        Some("emu") => {
            args.remove(0);
            setup(&opts).and_then(|found| run_cargo(&found, &emu_args(&args)))
        }
        _ => {
            let mut print_env = false;
            for a in &args {
                match a.to_str() {
                    Some("--user") => opts.user_only = true,
                    Some("--dev") => opts.dev = true,
                    Some("--env") => print_env = true,
                    Some("-h" | "--help") => {
                        print!("{HELP}");
                        return ExitCode::SUCCESS;
                    }
                    _ => {
                        eprintln!("inkstep setup: unknown argument {a:?} (cargo setup --help)");
                        return ExitCode::from(2);
                    }
                }
            }
            opts.quiet = print_env;
            setup(&opts).map(|found| {
                if print_env {
                    print!("{}", found.shell_exports());
                } else {
                    for line in &found.report {
                        println!("{line}");
                    }
                }
            })
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("inkstep setup: {e}");
            ExitCode::FAILURE
        }
    }
}

const HELP: &str = "\
cargo setup [--user] [--dev] [--env]
  Finds or installs what the tests and the emulator need (the thumbv7m-none-eabi target,
  flip-link, cmake, libclang) and says where each one is. `cargo test-host` and
  `cargo emu` run it first by themselves.
  --user  never use the system's packages, even as root: tools go to .tools/ (PyPI wheels)
          and $CARGO_HOME/bin (also: INKSTEP_SETUP=user)
  --dev   also the rustup components the checks use (rustfmt, clippy)
  --env   print the environment as shell exports, for cargo commands run by hand:
          eval \"$(cargo setup --env)\"
";

struct Options {
    /// Skip the system's tools and packages.
    user_only: bool,
    /// Also the lint components.
    dev: bool,
    /// Say only what is installed (the test and emulator commands), not where all is.
    quiet: bool,
}

/// The environment the builds need, and a line per tool for `cargo setup`.
#[derive(Default)]
struct Found {
    /// Directories to put in front of `PATH`.
    path: Vec<PathBuf>,
    /// Variables to set.
    vars: Vec<(&'static str, OsString)>,
    report: Vec<String>,
}

impl Found {
    fn shell_exports(&self) -> String {
        let mut out = String::new();
        if !self.path.is_empty() {
            let dirs: Vec<String> = self.path.iter().map(|p| p.display().to_string()).collect();
            out += &format!("export PATH={}:\"$PATH\"\n", quote(&dirs.join(":")));
        }
        for (k, v) in &self.vars {
            out += &format!("export {k}={}\n", quote(&v.to_string_lossy()));
        }
        out
    }

    fn apply(&self, cmd: &mut Command) {
        if !self.path.is_empty() {
            let mut dirs = self.path.clone();
            dirs.extend(env::split_paths(&env::var_os("PATH").unwrap_or_default()));
            if let Ok(joined) = env::join_paths(dirs) {
                cmd.env("PATH", joined);
            }
        }
        for (k, v) in &self.vars {
            cmd.env(k, v);
        }
    }
}

fn quote(s: &str) -> String {
    format!("'{}'", s.replace('\'', "'\\''"))
}

/// The project's root (this crate is one level down).
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_default()
}

fn setup(opts: &Options) -> Result<Found, String> {
    let mut found = Found::default();
    let ctx = Context::new(opts);
    target(&ctx, &mut found)?;
    flip_link(&ctx, &mut found)?;
    cmake(&ctx, &mut found)?;
    libclang(&ctx, &mut found)?;
    if opts.dev {
        components(&ctx, &mut found)?;
    }
    Ok(found)
}

/// What every step needs to know about this machine.
struct Context<'a> {
    opts: &'a Options,
    root: PathBuf,
    tools: PathBuf,
    is_root: bool,
}

impl<'a> Context<'a> {
    fn new(opts: &'a Options) -> Self {
        let root = root();
        Context {
            opts,
            // INKSTEP_TOOLS: another folder for what the set-up installs without root.
            tools: env::var_os("INKSTEP_TOOLS")
                .map(PathBuf::from)
                .unwrap_or_else(|| root.join(".tools")),
            root,
            is_root: running_as_root(),
        }
    }

    fn say(&self, what: &str) {
        eprintln!("inkstep setup: {what}");
    }

    /// Whether the system's packages may be installed: root, apt-get, and not `--user`.
    fn may_use_apt(&self) -> bool {
        !self.opts.user_only && self.is_root && on_path("apt-get").is_some()
    }
}

fn running_as_root() -> bool {
    // /proc/self/status: "Uid:\t<real>\t<effective>...".
    if let Ok(status) = fs::read_to_string("/proc/self/status") {
        if let Some(line) = status.lines().find(|l| l.starts_with("Uid:")) {
            return line.split_whitespace().nth(2) == Some("0");
        }
    }
    output("id", &["-u"]).is_some_and(|s| s.trim() == "0")
}

/// A command's standard output when it ran and succeeded.
fn output(program: impl AsRef<OsStr>, args: &[&str]) -> Option<String> {
    let out = Command::new(program)
        .args(args)
        .current_dir(root())
        .stderr(Stdio::null())
        .output()
        .ok()?;
    out.status
        .success()
        .then(|| String::from_utf8_lossy(&out.stdout).into_owned())
}

/// Runs an install step, its output shown, and says whether it succeeded.
fn run_step(program: impl AsRef<OsStr>, args: &[&str], envs: &[(&str, &str)]) -> bool {
    let mut cmd = Command::new(program);
    cmd.args(args).current_dir(root());
    for (k, v) in envs {
        cmd.env(k, v);
    }
    cmd.status().is_ok_and(|s| s.success())
}

/// The first executable called `name` in `PATH`.
fn on_path(name: &str) -> Option<PathBuf> {
    env::split_paths(&env::var_os("PATH")?)
        .map(|dir| dir.join(name))
        .find(|p| is_executable(p))
}

/// Whether a path is the system's (its package manager's), which `--user` leaves alone.
fn is_system(p: &Path) -> bool {
    ["/usr", "/bin", "/sbin", "/opt", "/lib"]
        .iter()
        .any(|dir| p.starts_with(dir))
}

fn is_executable(p: &Path) -> bool {
    use std::os::unix::fs::PermissionsExt;
    fs::metadata(p).is_ok_and(|m| m.is_file() && m.permissions().mode() & 0o111 != 0)
}

/// Debian's packages, as root: the lists are fetched first if the machine never did.
fn apt_install(ctx: &Context, packages: &[&str]) -> bool {
    ctx.say(&format!(
        "installing {} from Debian's packages (apt-get)",
        packages.join(" ")
    ));
    let env = [("DEBIAN_FRONTEND", "noninteractive")];
    let mut args = vec!["install", "-y", "-qq", "--no-install-recommends"];
    args.extend_from_slice(packages);
    run_step("apt-get", &args, &env)
        || (run_step("apt-get", &["update", "-qq"], &env) && run_step("apt-get", &args, &env))
}

/// A pinned wheel from PyPI into `.tools/<dir>`, with no root.
fn pip_install(ctx: &Context, wheel: &str, dir: &str) -> Result<(), String> {
    let python = on_path("python3").ok_or("python3 is not installed")?;
    if output(&python, &["-m", "pip", "--version"]).is_none() {
        return Err("python3 has no pip".into());
    }
    ctx.say(&format!(
        "installing {wheel} from PyPI into {}",
        ctx.tools.join(dir).display()
    ));
    let target = ctx.tools.join(dir);
    let target = target.to_string_lossy();
    let args = [
        "-m",
        "pip",
        "install",
        "--quiet",
        "--disable-pip-version-check",
        "--no-warn-script-location",
        "--root-user-action=ignore",
        "--target",
        &target,
        wheel,
    ];
    if run_step(&python, &args, &[]) {
        Ok(())
    } else {
        Err(format!("pip install {wheel} failed"))
    }
}

fn target(ctx: &Context, found: &mut Found) -> Result<(), String> {
    let installed = |sysroot: &str| Path::new(sysroot.trim()).join("lib/rustlib").join(TARGET);
    let sysroot = output("rustc", &["--print", "sysroot"])
        .ok_or("rustc does not run: install Rust with rustup (https://rustup.rs)")?;
    let mut dir = installed(&sysroot);
    if !dir.join("lib").is_dir() {
        if on_path("rustup").is_none() {
            return Err(format!(
                "the {TARGET} target is missing and rustup is not installed: add the target \
                 to your Rust toolchain ({})",
                sysroot.trim()
            ));
        }
        ctx.say(&format!("adding the {TARGET} target (rustup)"));
        if !run_step("rustup", &["target", "add", TARGET], &[]) || !dir.join("lib").is_dir() {
            return Err(format!(
                "the {TARGET} target could not be added: run `rustup target add {TARGET}` \
                 in {}",
                ctx.root.display()
            ));
        }
        dir = installed(&sysroot);
    }
    found
        .report
        .push(format!("target    {TARGET}: {}", dir.display()));
    Ok(())
}

fn cargo_home() -> PathBuf {
    env::var_os("CARGO_HOME")
        .map(PathBuf::from)
        .or_else(|| env::var_os("HOME").map(|h| Path::new(&h).join(".cargo")))
        .unwrap_or_else(|| PathBuf::from(".cargo"))
}

fn flip_link(ctx: &Context, found: &mut Found) -> Result<(), String> {
    let in_cargo_home = cargo_home().join("bin/flip-link");
    let located = on_path("flip-link")
        .or_else(|| is_executable(&in_cargo_home).then(|| in_cargo_home.clone()));
    let path = match located {
        Some(p) => p,
        None => {
            ctx.say(&format!(
                "installing {FLIP_LINK} (cargo install, into {})",
                cargo_home().join("bin").display()
            ));
            let cargo = env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
            // Outside the project, so that its target and profile settings do not apply.
            let ok = Command::new(cargo)
                .args(["install", "--locked", "--quiet", FLIP_LINK])
                .current_dir(env::temp_dir())
                .env_remove("CARGO_TARGET_DIR")
                .status()
                .is_ok_and(|s| s.success());
            if !ok || !is_executable(&in_cargo_home) {
                return Err(format!(
                    "flip-link (the firmware's linker) is missing and `cargo install {FLIP_LINK}` failed"
                ));
            }
            in_cargo_home
        }
    };
    if on_path("flip-link").is_none() {
        if let Some(dir) = path.parent() {
            found.path.push(dir.to_path_buf());
        }
    }
    found
        .report
        .push(format!("linker    flip-link: {}", path.display()));
    Ok(())
}

fn cmake(ctx: &Context, found: &mut Found) -> Result<(), String> {
    let wheel_bin = ctx.tools.join("cmake/cmake/data/bin/cmake");
    let system = on_path("cmake").filter(|p| !(ctx.opts.user_only && is_system(p)));
    let path = match system.or_else(|| is_executable(&wheel_bin).then(|| wheel_bin.clone())) {
        Some(p) => p,
        None => {
            let mut why = String::new();
            if ctx.may_use_apt() && apt_install(ctx, &["cmake"]) {
                on_path("cmake").ok_or("apt-get installed cmake, but it is not on PATH")?
            } else {
                if let Err(e) = pip_install(ctx, CMAKE_WHEEL, "cmake") {
                    why = e;
                }
                if !is_executable(&wheel_bin) {
                    return Err(format!(
                        "cmake (to build the emulator's CPU) is missing and could not be installed \
                         ({why}): install it with `sudo apt-get install cmake` or \
                         `python3 -m pip install --user '{CMAKE_WHEEL}'`"
                    ));
                }
                wheel_bin
            }
        }
    };
    if on_path("cmake").as_deref() != Some(path.as_path()) {
        // The wheel's: the cmake crate runs $CMAKE when it is set. (A cmake on PATH is
        // left to be found as a plain `cargo build` finds it, so that both build alike.)
        found.vars.push(("CMAKE", path.clone().into_os_string()));
        if let Some(dir) = path.parent() {
            found.path.push(dir.to_path_buf());
        }
    }
    let version = output(&path, &["--version"]).unwrap_or_default();
    let version = version
        .lines()
        .next()
        .unwrap_or("")
        .trim_start_matches("cmake version ");
    if version.starts_with(|c: char| c.is_ascii_digit() && c >= '4') {
        // unicorn asks for cmake 3.x's compatibility, which cmake 4 keeps only when told.
        found
            .vars
            .push(("CMAKE_POLICY_VERSION_MINIMUM", "3.5".into()));
    }
    found
        .report
        .push(format!("cmake     {version}: {}", path.display()));
    Ok(())
}

/// Whether a file name is one that clang-sys loads as libclang (`libclang.so`,
/// `libclang.so.14`, `libclang-14.so.1`; not `libclang-cpp`).
fn is_libclang(name: &str) -> bool {
    if name.starts_with("libclang-cpp") {
        return false;
    }
    name == "libclang.so"
        || name.starts_with("libclang.so.")
        || (name.starts_with("libclang-") && name.contains(".so"))
}

fn libclang_in(dir: &Path) -> Option<PathBuf> {
    fs::read_dir(dir)
        .ok()?
        .flatten()
        .map(|e| e.path())
        .find(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(is_libclang)
                && p.is_file()
        })
}

/// The directories clang-sys (bindgen's loader) searches when LIBCLANG_PATH is unset:
/// the library path variables, then /usr/local and /usr's lib folders two levels down.
fn system_libclang() -> Option<PathBuf> {
    let mut dirs: Vec<PathBuf> = Vec::new();
    if let Some(prefix) = output("llvm-config", &["--prefix"]) {
        let prefix = PathBuf::from(prefix.trim());
        dirs.extend(["bin", "lib", "lib64"].map(|d| prefix.join(d)));
    }
    for var in ["LD_LIBRARY_PATH", "LIBRARY_PATH"] {
        if let Some(v) = env::var_os(var) {
            dirs.extend(env::split_paths(&v));
        }
    }
    for base in ["/usr/local", "/usr"] {
        let Ok(entries) = fs::read_dir(base) else {
            continue;
        };
        let mut libs: Vec<PathBuf> = entries
            .flatten()
            .map(|e| e.path())
            .filter(|p| {
                p.file_name().and_then(|n| n.to_str()).is_some_and(|n| {
                    n.starts_with("lib") || (base == "/usr/local" && n.starts_with("llvm"))
                })
            })
            .collect();
        libs.sort();
        for lib in libs {
            dirs.push(lib.clone());
            for sub in subdirs(&lib) {
                dirs.extend(subdirs(&sub));
                dirs.push(sub);
            }
        }
    }
    dirs.iter().find_map(|d| libclang_in(d))
}

fn subdirs(dir: &Path) -> Vec<PathBuf> {
    let mut out: Vec<PathBuf> = fs::read_dir(dir)
        .map(|rd| {
            rd.flatten()
                .map(|e| e.path())
                .filter(|p| p.is_dir())
                .collect()
        })
        .unwrap_or_default();
    out.sort();
    out
}

fn libclang(ctx: &Context, found: &mut Found) -> Result<(), String> {
    let wheel_dir = ctx.tools.join("libclang/clang/native");
    if let Some(p) = env::var_os("LIBCLANG_PATH") {
        let p = PathBuf::from(p);
        let lib = if p.is_dir() {
            libclang_in(&p)
        } else {
            p.is_file().then_some(p.clone())
        };
        let lib = lib
            .ok_or_else(|| format!("LIBCLANG_PATH is {}, which holds no libclang", p.display()))?;
        found
            .report
            .push(format!("libclang  {} (LIBCLANG_PATH)", lib.display()));
        return Ok(());
    }
    let system = if ctx.opts.user_only {
        None
    } else {
        system_libclang()
    };
    if let Some(lib) = system {
        found.report.push(format!("libclang  {}", lib.display()));
        return Ok(());
    }
    let mut lib = libclang_in(&wheel_dir);
    if lib.is_none() && ctx.may_use_apt() && apt_install(ctx, &["libclang-dev"]) {
        if let Some(sys) = system_libclang() {
            found.report.push(format!("libclang  {}", sys.display()));
            return Ok(());
        }
    }
    let mut why = String::new();
    if lib.is_none() {
        if let Err(e) = pip_install(ctx, LIBCLANG_WHEEL, "libclang") {
            why = e;
        }
        lib = libclang_in(&wheel_dir);
    }
    let lib = lib.ok_or_else(|| {
        format!(
            "libclang (for the emulator's CPU bindings) is missing and could not be installed \
             ({why}): install it with `sudo apt-get install libclang-dev` or \
             `python3 -m pip install --user '{LIBCLANG_WHEEL}'` and set LIBCLANG_PATH"
        )
    })?;
    found
        .vars
        .push(("LIBCLANG_PATH", wheel_dir.into_os_string()));
    // The wheel carries the library without clang's own headers (stddef.h, stdbool.h):
    // the C compiler's are as good for the declarations bindgen reads.
    if let Some(include) = output("cc", &["-print-file-name=include"]) {
        let include = include.trim();
        if Path::new(include).join("stddef.h").is_file() {
            found.vars.push((
                "BINDGEN_EXTRA_CLANG_ARGS",
                format!("-isystem {include}").into(),
            ));
        }
    }
    found.report.push(format!("libclang  {}", lib.display()));
    Ok(())
}

fn components(ctx: &Context, found: &mut Found) -> Result<(), String> {
    let installed = output("rustup", &["component", "list", "--installed"]).unwrap_or_default();
    for c in DEV_COMPONENTS {
        let have = installed
            .lines()
            .any(|l| l.starts_with(&format!("{c}-")) || l == c);
        if !have {
            ctx.say(&format!("adding the {c} component (rustup)"));
            if !run_step("rustup", &["component", "add", c], &[]) {
                return Err(format!(
                    "could not add the {c} component: run `rustup component add {c}`"
                ));
            }
        }
        found.report.push(format!("component {c}"));
    }
    Ok(())
}

/// `cargo test-host [ARGS]`: every host test of the workspace (the firmware crate's
/// own tests run on a board: `cargo test`), ARGS passed on.
fn test_args(extra: &[OsString]) -> Vec<OsString> {
    let mut args: Vec<OsString> = [
        "test",
        "--workspace",
        "--exclude",
        "inkstep",
        "--target",
        "host-tuple",
        "--profile",
        "host",
    ]
    .iter()
    .map(OsString::from)
    .collect();
    args.extend_from_slice(extra);
    args
}

/// `cargo emu ARGS`: the emulator's command line.
fn emu_args(extra: &[OsString]) -> Vec<OsString> {
    let mut args: Vec<OsString> = [
        "run",
        "-q",
        "-p",
        "inkstep-emu",
        "--target",
        "host-tuple",
        "--profile",
        "host",
        "--",
    ]
    .iter()
    .map(OsString::from)
    .collect();
    args.extend_from_slice(extra);
    args
}

/// Replaces this process with cargo in the set-up environment.
fn run_cargo(found: &Found, args: &[OsString]) -> Result<(), String> {
    use std::os::unix::process::CommandExt;
    let cargo = env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let mut cmd = Command::new(&cargo);
    cmd.args(args)
        .current_dir(env::current_dir().unwrap_or_else(|_| root()));
    found.apply(&mut cmd);
    let err = cmd.exec();
    Err(format!(
        "could not run {}: {err}",
        Path::new(&cargo).display()
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn libclang_names_are_those_clang_sys_loads() {
        for name in [
            "libclang.so",
            "libclang.so.14",
            "libclang-14.so.1",
            "libclang-18.so",
        ] {
            assert!(is_libclang(name), "{name}");
        }
        for name in [
            "libclang-cpp.so.14",
            "libclangBasic.a",
            "libclang.a",
            "clang",
        ] {
            assert!(!is_libclang(name), "{name}");
        }
    }

    #[test]
    fn exports_quote_for_the_shell() {
        let found = Found {
            path: vec![PathBuf::from("/a b/bin")],
            vars: vec![("BINDGEN_EXTRA_CLANG_ARGS", "-isystem /it's".into())],
            report: vec![],
        };
        assert_eq!(
            found.shell_exports(),
            "export PATH='/a b/bin':\"$PATH\"\nexport BINDGEN_EXTRA_CLANG_ARGS='-isystem /it'\\''s'\n"
        );
    }

    #[test]
    fn test_and_emu_pass_their_arguments_on() {
        let extra = [OsString::from("bench"), OsString::from("--quick")];
        let emu = emu_args(&extra);
        let tail: Vec<OsString> = ["--", "bench", "--quick"].map(OsString::from).to_vec();
        assert_eq!(&emu[emu.len() - 3..], tail.as_slice());
        let test = test_args(&[OsString::from("--no-run")]);
        assert_eq!(test.last(), Some(&OsString::from("--no-run")));
        assert!(test.iter().any(|a| a == "host-tuple"));
    }
}
