//! A small fuzzing harness for the parsers a user feeds (used by `tests/fuzz.rs` and, for
//! longer runs, `benches/fuzz.rs`).
//!
//! A [`Target`] names a parser, the [`Format`] its input has (which picks the
//! structure-aware mutations, see [`mutate`]), real valid inputs to start from, and a `feed`
//! function that hands one input to the library and checks what comes back ([`Fed`]). Each
//! case is a seed mutated by a generator seeded from the target's name and the case's
//! number, so a failure is reproduced by its number alone. A case must not panic (caught),
//! must not hang (a per-case time limit), and must either be refused with a one-line error
//! that names something (`what: why`) or be accepted with a value free of NaN and infinity.
//!
//! A new parser is one more row of [`targets::all`]: its name, format, seeds and feed.
#![allow(dead_code)]

pub mod binary;
pub mod dictionary;
#[path = "../object_support/gltf.rs"]
pub mod gltf_files;
pub mod mutate;
pub mod seeds;
pub mod targets;

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// What a parser made of one input.
#[derive(Debug)]
pub enum Fed {
    /// Refused, with the library's error message.
    Refused(String),
    /// Accepted, and the value passed its checks.
    Accepted,
    /// Accepted, but the value is unsound (NaN, infinity, a size that does not add up).
    Unsound(String),
}

/// The shape of a target's input, which picks its mutations.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Format {
    Json,
    /// One JSON document per line.
    JsonLines,
    Toml,
    Obj,
    Png,
    Glb,
    /// A short text such as `rotation=30` or a pose's numbers.
    Words,
}

/// A parser under test.
pub struct Target {
    pub name: &'static str,
    pub format: Format,
    /// Real valid inputs to mutate.
    pub seeds: fn() -> Vec<Vec<u8>>,
    /// Hands `input` to the library (writing it under `dir` first where the parser reads a
    /// file) and checks the outcome.
    pub feed: fn(&Path, &[u8]) -> Fed,
    /// Cases run by `tests/fuzz.rs` (the CI budget).
    pub ci_cases: usize,
}

/// A deterministic generator (SplitMix64).
#[derive(Debug, Clone)]
pub struct Rng(u64);

impl Rng {
    pub fn new(parts: &[u64]) -> Rng {
        let mut r = Rng(0x853c_49e6_748f_ea9b);
        for &p in parts {
            r.0 ^= p;
            r.next();
        }
        r
    }

    pub fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// A number in `0..n` (`n > 0`).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }

    /// True with probability `p`.
    pub fn chance(&mut self, p: f64) -> bool {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64 <= p
    }

    pub fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }
}

/// 64-bit FNV-1a of a name: a target's generator seed.
pub fn name_hash(name: &str) -> u64 {
    name.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ b as u64).wrapping_mul(0x0100_0000_01b3)
    })
}

/// Case `k` of `target`: a mutated seed (case 0..seeds are the seeds themselves).
pub fn case(target: &Target, seeds: &[Vec<u8>], k: usize) -> Vec<u8> {
    if k < seeds.len() {
        return seeds[k].clone();
    }
    let mut rng = Rng::new(&[name_hash(target.name), k as u64]);
    let seed = rng.pick(seeds).clone();
    mutate::mutate(target.format, &mut rng, &seed, seeds)
}

/// A case that failed, and how.
#[derive(Debug)]
pub struct Failure {
    pub case: usize,
    pub what: String,
    /// Where its input was saved.
    pub input: PathBuf,
}

/// What a run of one target found.
#[derive(Debug)]
pub struct Report {
    pub name: &'static str,
    pub cases: usize,
    pub refused: usize,
    pub accepted: usize,
    /// Accepted cases that are mutations, not seeds: the mutations reach past the syntax.
    pub mutants_accepted: usize,
    pub slowest: Duration,
    pub slowest_case: usize,
    pub wall: Duration,
    /// Of the wall time, making the cases (mutating).
    pub making: Duration,
    pub failures: Vec<Failure>,
}

/// The time one case may take before it counts as a hang: generous for the dev profile on a
/// busy 2-core machine, far below what a real hang takes.
pub const CASE_LIMIT: Duration = Duration::from_secs(20);

/// What the worker hands back for case k: the outcome (or the panic's message) and the time
/// the feed took.
type Answer = (usize, Result<Fed, String>, Duration);

/// Runs `cases` cases of `target` on a worker thread, each within [`CASE_LIMIT`]. Stops at
/// a hang (the worker cannot be stopped) and after 20 failures.
pub fn run(target: &'static Target, cases: usize) -> Report {
    let started = Instant::now();
    let dir = work_dir(target.name);
    let scratch = scratch_dir(target.name);
    let seeds = (target.seeds)();
    assert!(!seeds.is_empty(), "{}: no seeds", target.name);
    let (to_worker, outbox) = worker(target, scratch.clone());
    let mut report = Report {
        name: target.name,
        cases: 0,
        refused: 0,
        accepted: 0,
        mutants_accepted: 0,
        slowest: Duration::ZERO,
        slowest_case: 0,
        wall: Duration::ZERO,
        making: Duration::ZERO,
        failures: Vec::new(),
    };
    for k in 0..cases {
        let made = Instant::now();
        let input = case(target, &seeds, k);
        report.making += made.elapsed();
        if to_worker.send((k, input.clone())).is_err() {
            break;
        }
        let Ok((_, fed, took)) = outbox.recv_timeout(CASE_LIMIT) else {
            let what = format!("hang: no answer within {CASE_LIMIT:?}");
            report.failures.push(save(&dir, target, k, what, &input));
            break;
        };
        report.cases += 1;
        if took > report.slowest {
            report.slowest = took;
            report.slowest_case = k;
            let _ = std::fs::write(
                dir.join(format!("slowest.{}", extension(target.format))),
                &input,
            );
        }
        match judge(fed) {
            Ok(true) => {
                report.accepted += 1;
                report.mutants_accepted += usize::from(k >= seeds.len());
            }
            Ok(false) => report.refused += 1,
            Err(what) => report.failures.push(save(&dir, target, k, what, &input)),
        }
        if report.failures.len() >= 20 {
            break;
        }
    }
    drop(to_worker);
    if report.failures.iter().all(|f| !f.what.starts_with("hang")) {
        let _ = std::fs::remove_dir_all(&scratch);
        // The process's directory, once its last target is done.
        let _ = scratch.parent().map(std::fs::remove_dir);
    }
    report.wall = started.elapsed();
    report
}

/// A thread that feeds the cases it is sent to `target`, each in a fresh directory under
/// `scratch`, catching panics.
fn worker(
    target: &'static Target,
    scratch: PathBuf,
) -> (mpsc::Sender<(usize, Vec<u8>)>, mpsc::Receiver<Answer>) {
    let (to_worker, inbox) = mpsc::channel::<(usize, Vec<u8>)>();
    let (to_main, outbox) = mpsc::channel::<Answer>();
    std::thread::Builder::new()
        .name(format!("fuzz {}", target.name))
        // Deeply nested inputs recurse in some parsers; give them the main thread's stack.
        .stack_size(64 << 20)
        .spawn(move || {
            for (k, input) in inbox {
                let case_dir = scratch.join(format!("case{}", k % 4));
                let _ = std::fs::remove_dir_all(&case_dir);
                let _ = std::fs::create_dir_all(&case_dir);
                let start = Instant::now();
                let fed = catch_unwind(AssertUnwindSafe(|| (target.feed)(&case_dir, &input)))
                    .map_err(|p| panic_text(&*p));
                if to_main.send((k, fed, start.elapsed())).is_err() {
                    return;
                }
            }
        })
        .expect("cannot start a fuzz worker");
    (to_worker, outbox)
}

/// Ok(accepted?) for a sound outcome, or what is wrong with it.
fn judge(fed: Result<Fed, String>) -> Result<bool, String> {
    match fed {
        Err(panic) => Err(format!("panic: {panic}")),
        Ok(Fed::Unsound(why)) => Err(format!("accepted an unsound value: {why}")),
        Ok(Fed::Accepted) => Ok(true),
        Ok(Fed::Refused(message)) => {
            if message.contains('\n') || message.contains('\r') {
                Err(format!("error of several lines: {message:?}"))
            } else if !message.contains(": ") || message.trim().len() < 8 {
                Err(format!("error that names nothing: {message:?}"))
            } else {
                Ok(false)
            }
        }
    }
}

fn panic_text(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "no message".into())
}

/// Saves a failing case's input under the target's directory.
fn save(dir: &Path, target: &Target, k: usize, what: String, input: &[u8]) -> Failure {
    let path = dir.join(format!("failure-{k}.{}", extension(target.format)));
    let _ = std::fs::write(&path, input);
    Failure {
        case: k,
        what,
        input: path,
    }
}

/// The file extension an input of `format` is written with.
pub fn extension(format: Format) -> &'static str {
    match format {
        Format::Json => "json",
        Format::JsonLines => "jsonl",
        Format::Toml => "toml",
        Format::Obj => "obj",
        Format::Png => "png",
        Format::Glb => "glb",
        Format::Words => "txt",
    }
}

/// A fresh directory for a target's cases to write their files in: in memory where the
/// machine has a tmpfs (the dataset's files are synced to disk as they are written, which
/// on a disk costs more than the parsing under test), else as [`work_dir`].
fn scratch_dir(name: &str) -> PathBuf {
    let shm = Path::new("/dev/shm");
    if !shm.is_dir() {
        return work_dir(&format!("{name} scratch"));
    }
    let dir = shm
        .join(format!("geltip-fuzz-{}", std::process::id()))
        .join(name.replace([' ', '/', '.'], "_"));
    let _ = std::fs::remove_dir_all(&dir);
    match std::fs::create_dir_all(&dir) {
        Ok(()) => dir,
        Err(_) => work_dir(&format!("{name} scratch")),
    }
}

/// A fresh directory for a target's failing inputs, under the build's target directory.
fn work_dir(name: &str) -> PathBuf {
    let root = option_env!("CARGO_TARGET_TMPDIR")
        .map(PathBuf::from)
        .unwrap_or_else(std::env::temp_dir);
    let dir = root.join("fuzz").join(name.replace([' ', '/', '.'], "_"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("cannot create the fuzz directory");
    dir
}

/// The columns of [`row`].
pub fn header() -> String {
    format!(
        "{:<26} {:>7} {:>7} {:>7} {:>11} {:>7} {:>7} {:>7}",
        "parser", "cases", "errors", "ok", "slowest ms", "case", "wall s", "make s"
    )
}

/// A report as one row: cases, refused (errors), accepted (ok), the slowest case's time and
/// number, the wall time and the part of it spent making the cases.
pub fn row(r: &Report) -> String {
    format!(
        "{:<26} {:>7} {:>7} {:>7} {:>11.1} {:>7} {:>7.1} {:>7.1}",
        r.name,
        r.cases,
        r.refused,
        r.accepted,
        r.slowest.as_secs_f64() * 1e3,
        r.slowest_case,
        r.wall.as_secs_f64(),
        r.making.as_secs_f64()
    )
}

/// A report's row and its failures below it.
pub fn describe(r: &Report) -> String {
    let mut s = row(r);
    for f in &r.failures {
        s.push_str(&format!(
            "\n  case {}: {} (input: {})",
            f.case,
            f.what,
            f.input.display()
        ));
    }
    s
}
