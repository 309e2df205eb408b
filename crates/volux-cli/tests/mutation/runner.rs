//! Runs the `volux` binary as a child process under an address-space limit and a
//! wall-clock timeout, and checks what a hostile input may and may not do to it.
use std::collections::BTreeSet;
use std::fmt;
use std::fs::File;
use std::os::unix::process::ExitStatusExt;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Address-space limit of each child (bytes).
pub const ADDRESS_SPACE: u64 = 2 << 30;
/// Wall-clock limit of each child.
pub const TIMEOUT: Duration = Duration::from_secs(20);

/// What a finished (or killed) child did.
#[derive(Debug)]
pub struct Outcome {
    /// The exit code, `None` when a signal ended it.
    pub code: Option<i32>,
    /// The signal that ended it.
    pub signal: Option<i32>,
    /// Killed at the timeout.
    pub timed_out: bool,
    /// Its standard error, as bytes.
    pub stderr: Vec<u8>,
}

impl Outcome {
    /// Exited with code 0.
    pub fn ok(&self) -> bool {
        self.code == Some(0)
    }

    /// The first line of standard error (lossy UTF-8, control characters escaped).
    pub fn first_line(&self) -> String {
        let text = String::from_utf8_lossy(&self.stderr);
        let line = text.lines().next().unwrap_or("").to_string();
        let line: String = line.escape_debug().collect();
        line.chars().take(300).collect()
    }
}

/// The ways a run can go wrong.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Kind {
    /// A Rust panic.
    Panic,
    /// `memory allocation of N bytes failed` (an abort on allocation failure).
    AllocAbort,
    /// Ended by a signal.
    Signal,
    /// Still running at the timeout.
    Hang,
    /// An exit code other than 0, 1 or 2.
    ExitCode,
    /// A failure whose standard error is not warnings then exactly one `volux: error:` line.
    ErrorFormat,
    /// Control characters (or invalid UTF-8) on standard error.
    ControlChars,
    /// `out.png` left behind by a failed render.
    PartialOutput,
    /// A successful render without `out.png`.
    MissingOutput,
    /// Files left in the folder (temporary files) or removed from it.
    StrayFiles,
}

impl fmt::Display for Kind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Debug::fmt(self, f)
    }
}

/// The `volux` binary under test.
pub fn volux_bin() -> &'static str {
    env!("CARGO_BIN_EXE_volux")
}

/// The address-space limit of each command: [`ADDRESS_SPACE`], or `VOLUX_MUTATION_AS`
/// bytes (a long run under 1 GiB shows that no case grows past it before its error).
fn address_space() -> u64 {
    std::env::var("VOLUX_MUTATION_AS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(ADDRESS_SPACE)
}

/// The command that runs `volux args` under the address-space limit: `prlimit` when it is
/// there, else `sh -c 'ulimit -v'`. Either way the child's pid is the `volux` process.
fn limited(args: &[String]) -> Command {
    let limit = address_space();
    let prlimit = Path::new("/usr/bin/prlimit");
    if prlimit.exists() {
        let mut c = Command::new(prlimit);
        c.arg(format!("--as={limit}")).arg("--").arg(volux_bin());
        c.args(args);
        c
    } else {
        let mut c = Command::new("sh");
        let kb = limit / 1024;
        c.arg("-c")
            .arg(format!("ulimit -v {kb}; exec \"$0\" \"$@\""));
        c.arg(volux_bin()).args(args);
        c
    }
}

/// Runs `volux args` in `dir`, its output going to `log` (`.out`, `.err`, outside `dir`),
/// killing it at the timeout.
pub fn run(args: &[String], dir: &Path, log: &Path) -> Outcome {
    let out = log.with_extension("out");
    let err = log.with_extension("err");
    let mut child = limited(args)
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(File::create(&out).expect("log file"))
        .stderr(File::create(&err).expect("log file"))
        .spawn()
        .expect("volux starts");
    let start = Instant::now();
    let mut timed_out = false;
    let status = loop {
        if let Some(s) = child.try_wait().expect("waiting for volux") {
            break s;
        }
        if start.elapsed() > TIMEOUT {
            timed_out = true;
            let _ = child.kill();
            break child.wait().expect("waiting for volux");
        }
        std::thread::sleep(poll_interval(start.elapsed()));
    };
    Outcome {
        code: status.code(),
        signal: status.signal(),
        timed_out,
        stderr: std::fs::read(&err).unwrap_or_default(),
    }
}

/// Polls fast at first (most runs take milliseconds), then every 20 ms.
fn poll_interval(elapsed: Duration) -> Duration {
    if elapsed < Duration::from_millis(100) {
        Duration::from_millis(1)
    } else {
        Duration::from_millis(20)
    }
}

/// The names in `dir` (empty if it cannot be read).
pub fn listing(dir: &Path) -> BTreeSet<String> {
    std::fs::read_dir(dir)
        .map(|rd| {
            rd.filter_map(Result::ok)
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .collect()
        })
        .unwrap_or_default()
}

/// Whether `bytes` hold a control character other than a newline, or invalid UTF-8.
fn has_control(bytes: &[u8]) -> bool {
    match std::str::from_utf8(bytes) {
        Ok(s) => s.chars().any(|c| c.is_control() && c != '\n'),
        Err(_) => true,
    }
}

/// Whether standard error is warnings followed by exactly one `volux: error:` line.
fn one_error_line(stderr: &[u8]) -> bool {
    let text = String::from_utf8_lossy(stderr);
    let lines: Vec<&str> = text.lines().collect();
    match lines.split_last() {
        Some((last, rest)) => {
            last.starts_with("volux: error: ")
                && rest.iter().all(|l| l.starts_with("volux: warning: "))
        }
        None => false,
    }
}

/// The crash of `o`, if any: a hang, an allocation abort, a panic, a signal or an odd exit
/// code (in that order of precedence).
fn crash(o: &Outcome) -> Option<Kind> {
    let text = String::from_utf8_lossy(&o.stderr);
    if o.timed_out {
        Some(Kind::Hang)
    } else if text.contains("memory allocation of") {
        Some(Kind::AllocAbort)
    } else if text.contains("panicked") {
        Some(Kind::Panic)
    } else if o.signal.is_some() {
        Some(Kind::Signal)
    } else if o.code.is_some_and(|c| !(0..=2).contains(&c)) {
        Some(Kind::ExitCode)
    } else {
        None
    }
}

/// The process-level failures of `o`: a crash, else a malformed error; control characters.
pub fn process_failures(o: &Outcome) -> Vec<Kind> {
    let mut v: Vec<Kind> = crash(o).into_iter().collect();
    if v.is_empty() && !o.ok() && !one_error_line(&o.stderr) {
        v.push(Kind::ErrorFormat);
    }
    if has_control(&o.stderr) {
        v.push(Kind::ControlChars);
    }
    v
}

/// The folder-level failures after a run: `before` is the listing before it, `png` whether
/// the command was a render.
pub fn folder_failures(
    o: &Outcome,
    before: &BTreeSet<String>,
    after: &BTreeSet<String>,
    png: bool,
) -> Vec<Kind> {
    let mut v = Vec::new();
    let made_png = !before.contains("out.png") && after.contains("out.png");
    if png && !o.ok() && made_png {
        v.push(Kind::PartialOutput);
    }
    if png && o.ok() && !after.contains("out.png") {
        v.push(Kind::MissingOutput);
    }
    let mut expected = before.clone();
    if png && o.ok() {
        expected.insert("out.png".to_string());
    }
    let stray = after
        .iter()
        .any(|n| !expected.contains(n) && n != "out.png");
    if stray || before.iter().any(|n| !after.contains(n)) {
        v.push(Kind::StrayFiles);
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn error_lines_are_checked() {
        assert!(one_error_line(b"volux: warning: a\nvolux: error: b\n"));
        assert!(!one_error_line(b"volux: error: b\nmore\n"));
        assert!(!one_error_line(b"volux: error: a\nvolux: error: b\n"));
        assert!(!one_error_line(b""));
        assert!(has_control(b"a\x1b[31m"));
        assert!(has_control(b"\xff"));
        assert!(!has_control(b"fine\n"));
    }
}
