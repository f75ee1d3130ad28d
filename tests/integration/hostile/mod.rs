//! The hostile-input suite (issue 56): every case of [`cases`] run through `vcm` as a separate
//! process under a 4 GiB address space limit (`RLIMIT_AS`) and a time limit. Each must end
//! with a clear error (exit status 1 and a message; 2 for a command-line usage error) or a
//! valid result, never a panic (101), a signal (an abort, the out-of-memory killer) or a hang;
//! and each must do what its case expects. The figures (cases, outcomes, peak memory) are
//! printed and kept in docs/testing.md.

mod cases;

use std::collections::BTreeMap;
use std::fs::File;
use std::os::unix::process::{CommandExt, ExitStatusExt};
use std::path::Path;
use std::process::{Command, ExitStatus, Stdio};
use std::time::{Duration, Instant};

use cases::{Case, Expect, Generator};

/// The address space each run may use.
const MEMORY_LIMIT: u64 = 4 << 30;
/// The wall-clock time each run may take.
const TIME_LIMIT: Duration = Duration::from_secs(30);

/// How one run ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Outcome {
    /// Exit status 0.
    Success,
    /// Exit status 1 or 2 with a message on stderr.
    CleanError,
    /// Exit status 101: a Rust panic.
    Panic,
    /// Ended by a signal: an abort, a stack overflow, the out-of-memory killer.
    Signal,
    /// Still running at the time limit (then killed).
    Hang,
    /// Any other exit status, or an error without a message.
    Other,
}

/// One finished run: how it ended, its stderr, its peak resident memory and wall time.
struct Run {
    outcome: Outcome,
    status: ExitStatus,
    stderr: String,
    peak_kib: i64,
    seconds: f64,
}

/// Runs `vcm` with `args` in the repository root under [`MEMORY_LIMIT`] and [`TIME_LIMIT`],
/// its stdout and stderr in files of `dir`; its peak memory from `wait4`.
fn run(args: &[String], dir: &Path) -> Run {
    let stderr_path = dir.join("stderr.txt");
    let mut command = Command::new(env!("CARGO_BIN_EXE_vcm"));
    command
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdin(Stdio::null())
        .stdout(File::create(dir.join("stdout.txt")).unwrap())
        .stderr(File::create(&stderr_path).unwrap());
    // SAFETY: between fork and exec the hook only calls setrlimit, which is async-signal-safe.
    unsafe {
        command.pre_exec(|| {
            let limit = libc::rlimit {
                rlim_cur: MEMORY_LIMIT,
                rlim_max: MEMORY_LIMIT,
            };
            if libc::setrlimit(libc::RLIMIT_AS, &limit) == 0 {
                Ok(())
            } else {
                Err(std::io::Error::last_os_error())
            }
        });
    }
    let start = Instant::now();
    // Reaped below by wait4, for its resource usage, not through std's `Child`.
    let pid = command.spawn().expect("the vcm binary starts").id() as libc::pid_t;
    // SAFETY: rusage is plain integers, for which all zeros is a valid value.
    let (mut status, mut usage) = (0, unsafe { std::mem::zeroed::<libc::rusage>() });
    let mut hung = false;
    loop {
        // SAFETY: wait4 writes the status and usage it is given; the child is ours.
        let reaped = unsafe { libc::wait4(pid, &mut status, libc::WNOHANG, &mut usage) };
        if reaped == pid {
            break;
        }
        assert_eq!(reaped, 0, "wait4 failed for {args:?}");
        if start.elapsed() > TIME_LIMIT && !hung {
            hung = true;
            // SAFETY: the child has not been reaped, so its pid is still its own.
            unsafe { libc::kill(pid, libc::SIGKILL) };
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    let status = ExitStatus::from_raw(status);
    let stderr = std::fs::read_to_string(&stderr_path).unwrap_or_default();
    let outcome = match (hung, status.code(), status.signal()) {
        (true, ..) => Outcome::Hang,
        (_, Some(0), _) => Outcome::Success,
        (_, Some(1 | 2), _) if stderr.contains("error") => Outcome::CleanError,
        (_, Some(101), _) => Outcome::Panic,
        (_, None, Some(_)) => Outcome::Signal,
        _ => Outcome::Other,
    };
    Run {
        outcome,
        status,
        stderr,
        peak_kib: usage.ru_maxrss,
        seconds: start.elapsed().as_secs_f64(),
    }
}

/// Why `run` of `case` is wrong, if it is.
fn judge(case: &Case, run: &Run) -> Option<String> {
    let wrong = match (case.expect, run.outcome) {
        (_, Outcome::Panic | Outcome::Signal | Outcome::Hang | Outcome::Other) => true,
        (Expect::Error(phrase), Outcome::CleanError) => !run.stderr.contains(phrase),
        (Expect::Error(_), Outcome::Success) => true,
        (Expect::Success, Outcome::CleanError) => true,
        (Expect::Success | Expect::Either, _) => false,
    };
    let output = case
        .args
        .iter()
        .position(|a| a == "-o")
        .map(|i| &case.args[i + 1]);
    let missing_image = run.outcome == Outcome::Success
        && case.args[0] == "render"
        && output.is_some_and(|o| !Path::new(o).is_file());
    (wrong || missing_image).then(|| {
        format!(
            "{} ({}): expected {:?}, got {:?} ({:?}{}) after {:.1} s:\n{}",
            case.name,
            case.class,
            case.expect,
            run.outcome,
            run.status,
            if missing_image { ", no image" } else { "" },
            run.seconds,
            run.stderr
        )
    })
}

#[test]
fn hostile_input_ends_in_a_clear_error_or_a_valid_result() {
    let dir = tempfile::tempdir().unwrap();
    let cases = Generator::new(dir.path()).all();
    let logs = tempfile::tempdir().unwrap();
    let start = Instant::now();
    let mut counts: BTreeMap<Outcome, usize> = BTreeMap::new();
    let mut classes: BTreeMap<&str, usize> = BTreeMap::new();
    let (mut peak_kib, mut peak_case, mut slowest) = (0, String::new(), (0.0, String::new()));
    let mut failures = Vec::new();
    for case in &cases {
        let run = run(&case.args, logs.path());
        *counts.entry(run.outcome).or_default() += 1;
        *classes.entry(case.class).or_default() += 1;
        if run.peak_kib > peak_kib {
            (peak_kib, peak_case) = (run.peak_kib, case.name.clone());
        }
        if run.seconds > slowest.0 {
            slowest = (run.seconds, case.name.clone());
        }
        failures.extend(judge(case, &run));
    }
    let count = |outcome| counts.get(&outcome).copied().unwrap_or(0);
    println!(
        "hostile input: {} cases ({classes:?}) in {:.1} s: {} clean errors, {} successes, \
         {} panics, {} signals, {} hangs, {} other; peak memory {:.0} MiB ({peak_case}); \
         slowest {:.2} s ({})",
        cases.len(),
        start.elapsed().as_secs_f64(),
        count(Outcome::CleanError),
        count(Outcome::Success),
        count(Outcome::Panic),
        count(Outcome::Signal),
        count(Outcome::Hang),
        count(Outcome::Other),
        peak_kib as f64 / 1024.0,
        slowest.0,
        slowest.1,
    );
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
    // Every class is there, and each case was judged by what it must give.
    assert!(classes.len() >= 8 && cases.len() >= 100, "{classes:?}");
    assert_eq!(
        count(Outcome::CleanError) + count(Outcome::Success),
        cases.len()
    );
}
