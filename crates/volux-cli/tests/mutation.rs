//! A seeded, deterministic mutation harness for hostile input (see `docs/hostile-input.md`).
//!
//! Valid seeds of every format ([`seeds`]) are mutated with `volux_testkit::mutate`; each case
//! runs `volux info FILE` and, when that succeeds, `volux render FILE --size 32x32 -o out.png`
//! (some cases with `--shade`, `--mip`, `--method pt --as-tets` on grids, `--method raycast`
//! on meshes) under a 2 GiB address-space limit and a 20 s timeout ([`runner`]). No run may
//! panic, abort, die of a signal or hang; a failure is warnings then exactly one
//! `volux: error:` line, without control characters; a failed render leaves no `out.png` and
//! no run leaves temporary files.
//!
//! `mutation_suite` runs 300 cases of a fixed seed; `mutation_long_run` (ignored) runs
//! `VOLUX_MUTATION_CASES` cases (default 20000) of seed `VOLUX_MUTATION_SEED` and prints a
//! summary. `VOLUX_MUTATION_ONLY=3,17` runs only those case indices (to reproduce one),
//! `VOLUX_MUTATION_KEEP=DIR` keeps the inputs of failing cases in `DIR`,
//! `VOLUX_MUTATION_FORMATS=dicom,tiff` runs only the seeds whose format starts so.
#[path = "mutation/runner.rs"]
mod runner;
#[path = "mutation/seeds.rs"]
mod seeds;

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use runner::{folder_failures, listing, process_failures, Kind};
use seeds::Seed;
use volux_testkit::mutate::{mutate, write_case, FsCase, Mutation};
use volux_testkit::TestRng;

/// The seed of the in-suite run.
const SUITE_SEED: u64 = 0x0076_6f6c_7578;
/// Cases of the in-suite run.
const SUITE_CASES: usize = 300;

/// One mutated input and the render options it gets.
struct Case {
    index: usize,
    format: &'static str,
    mutation: Mutation,
    target: String,
    render_extra: Vec<&'static str>,
}

/// One failure of a case.
struct Failure {
    kind: Kind,
    command: String,
    first_line: String,
}

/// What a case did.
struct CaseResult {
    index: usize,
    format: &'static str,
    what: String,
    skipped: bool,
    info_ok: bool,
    render_ok: Option<bool>,
    failures: Vec<Failure>,
}

/// The generator of case `index` of the run of `base` (independent of the other cases).
fn case_rng(base: u64, index: usize) -> TestRng {
    let mut rng = TestRng::new(base ^ (index as u64 + 1).wrapping_mul(0x9e37_79b9_7f4a_7c15));
    rng.next_u64();
    rng
}

/// The extra render options for a grid or a mesh (plain most of the time).
fn render_extra(mesh: bool, rng: &mut TestRng) -> Vec<&'static str> {
    let grid: [&[&'static str]; 6] = [
        &[],
        &[],
        &["--shade"],
        &["--mip"],
        &["--method", "pt", "--as-tets"],
        &[],
    ];
    let meshes: [&[&'static str]; 3] = [&[], &[], &["--method", "raycast"]];
    if mesh {
        meshes[rng.below(meshes.len())].to_vec()
    } else {
        grid[rng.below(grid.len())].to_vec()
    }
}

/// Case `index` of the run of `base`.
fn make_case(seeds: &[Seed], base: u64, index: usize) -> Case {
    let mut rng = case_rng(base, index);
    let seed = &seeds[rng.below(seeds.len())];
    let mutation = mutate(&seed.files, &mut rng);
    Case {
        index,
        format: seed.format,
        target: seed.target().to_string(),
        render_extra: render_extra(seed.mesh, &mut rng),
        mutation,
    }
}

/// The `render` arguments of a case.
fn render_args(case: &Case) -> Vec<String> {
    let mut a: Vec<String> = ["render", &case.target, "--size", "32x32", "-o", "out.png"]
        .iter()
        .map(ToString::to_string)
        .collect();
    a.extend(case.render_extra.iter().map(ToString::to_string));
    a
}

/// Runs one command of a case and records its failures; returns whether it succeeded.
fn step(args: &[String], dir: &Path, log: &Path, failures: &mut Vec<Failure>) -> bool {
    let before = listing(dir);
    let o = runner::run(args, dir, log);
    let after = listing(dir);
    let png = args[0] == "render";
    let mut kinds = process_failures(&o);
    kinds.extend(folder_failures(&o, &before, &after, png));
    let command = format!("volux {}", args.join(" "));
    for kind in kinds {
        failures.push(Failure {
            kind,
            command: command.clone(),
            first_line: o.first_line(),
        });
    }
    o.ok()
}

/// Runs `case` in a fresh folder under `root`; keeps the inputs of a failing case.
fn run_case(case: &Case, root: &Path, keep: Option<&Path>) -> CaseResult {
    let dir = root.join(format!("c{}", case.index));
    std::fs::create_dir_all(&dir).expect("case folder");
    let mut result = CaseResult {
        index: case.index,
        format: case.format,
        what: case.mutation.what.clone(),
        skipped: false,
        info_ok: false,
        render_ok: None,
        failures: Vec::new(),
    };
    if !write_case(&dir, &case.mutation).expect("writing the case") {
        result.skipped = true;
        return result;
    }
    let log = root.join(format!("log-{}", case.index));
    let info = vec!["info".to_string(), case.target.clone()];
    result.info_ok = step(&info, &dir, &log, &mut result.failures);
    if result.info_ok {
        let ok = step(&render_args(case), &dir, &log, &mut result.failures);
        result.render_ok = Some(ok);
    }
    if let (Some(keep), false) = (keep, result.failures.is_empty()) {
        keep_case(&dir, keep, case, &result);
    }
    let _ = std::fs::remove_dir_all(&dir);
    result
}

/// Copies a failing case's folder to `keep/case-INDEX-FORMAT` (links as links, FIFOs as a
/// note) with `case.txt` saying what failed.
fn keep_case(dir: &Path, keep: &Path, case: &Case, r: &CaseResult) {
    let to = keep.join(format!("case-{}-{}", case.index, case.format));
    let _ = std::fs::remove_dir_all(&to);
    if std::fs::create_dir_all(&to).is_err() {
        return;
    }
    for name in listing(dir) {
        copy_entry(&dir.join(&name), &to.join(&name));
    }
    let mut text = format!("format: {}\nmutation: {}\n", case.format, r.what);
    for f in &r.failures {
        text += &format!("{}: {}\n  stderr: {}\n", f.kind, f.command, f.first_line);
    }
    let _ = std::fs::write(to.join("case.txt"), text);
}

/// Copies one folder entry without following links or opening FIFOs.
fn copy_entry(from: &Path, to: &Path) {
    let Ok(meta) = std::fs::symlink_metadata(from) else {
        return;
    };
    if meta.file_type().is_symlink() {
        if let Ok(target) = std::fs::read_link(from) {
            let _ = std::os::unix::fs::symlink(target, to);
        }
    } else if meta.is_file() {
        let _ = std::fs::copy(from, to);
    } else if meta.is_dir() {
        let _ = std::fs::create_dir_all(to);
    } else {
        let _ = std::fs::write(
            to.with_extension("special.txt"),
            "a FIFO or other special file",
        );
    }
}

/// Runs the cases `indices` of the run of `base` on a few threads.
fn run_all(seeds: &[Seed], base: u64, indices: &[usize]) -> Vec<CaseResult> {
    let root = tempfile::tempdir().expect("temporary folder");
    let keep = std::env::var_os("VOLUX_MUTATION_KEEP").map(PathBuf::from);
    let next = AtomicUsize::new(0);
    let results = Mutex::new(Vec::new());
    let threads = std::thread::available_parallelism().map_or(2, |n| n.get().clamp(2, 4));
    std::thread::scope(|s| {
        for _ in 0..threads {
            s.spawn(|| loop {
                let i = next.fetch_add(1, Ordering::Relaxed);
                let Some(&index) = indices.get(i) else { break };
                let case = make_case(seeds, base, index);
                let r = run_case(&case, root.path(), keep.as_deref());
                results.lock().unwrap().push(r);
            });
        }
    });
    let mut v = results.into_inner().unwrap();
    v.sort_by_key(|r| r.index);
    v
}

/// Every seed must pass `volux info` and render before it is mutated.
fn check_seeds(seeds: &[Seed]) {
    let root = tempfile::tempdir().expect("temporary folder");
    for seed in seeds {
        let dir = root.path().join(seed.format);
        std::fs::create_dir_all(&dir).unwrap();
        let m = Mutation {
            files: seed
                .files
                .iter()
                .map(|f| (f.name.clone(), f.bytes.clone()))
                .collect(),
            fs: None,
            what: String::new(),
        };
        write_case(&dir, &m).unwrap();
        let log = root.path().join(format!("{}-log", seed.format));
        for args in [
            vec!["info"],
            vec!["render", "--size", "32x32", "-o", "out.png"],
        ] {
            let mut a: Vec<String> = args.iter().map(ToString::to_string).collect();
            a.insert(1, seed.target().to_string());
            let o = runner::run(&a, &dir, &log);
            assert!(
                o.ok(),
                "seed {} fails `volux {}`: {}",
                seed.format,
                a.join(" "),
                o.first_line()
            );
        }
    }
}

/// The case indices to run: `VOLUX_MUTATION_ONLY` (comma-separated) or `0..count`.
fn indices(count: usize) -> Vec<usize> {
    match std::env::var("VOLUX_MUTATION_ONLY") {
        Ok(list) => list
            .split(',')
            .filter_map(|s| s.trim().parse().ok())
            .collect(),
        Err(_) => (0..count).collect(),
    }
}

/// The failures, grouped by kind, at most `per_kind` examples each.
fn failure_report(results: &[CaseResult], base: u64, per_kind: usize) -> String {
    let mut by_kind: BTreeMap<Kind, Vec<(&CaseResult, &Failure)>> = BTreeMap::new();
    for r in results {
        for f in &r.failures {
            by_kind.entry(f.kind).or_default().push((r, f));
        }
    }
    let mut out = String::new();
    for (kind, list) in &by_kind {
        out += &format!("{kind}: {} failures\n", list.len());
        for (r, f) in list.iter().take(per_kind) {
            out += &format!(
                "  case {} (VOLUX_MUTATION_SEED={base} VOLUX_MUTATION_ONLY={}) format {}, mutation [{}]\n    command: {}\n    stderr: {}\n",
                r.index, r.index, r.format, r.what, f.command, f.first_line
            );
        }
    }
    out
}

/// Counts per format, outcomes and failure kinds, and the speed.
fn summary(results: &[CaseResult], wall: Duration) -> String {
    let mut formats: BTreeMap<&str, usize> = BTreeMap::new();
    let mut kinds: BTreeMap<Kind, usize> = BTreeMap::new();
    for r in results {
        *formats.entry(r.format).or_default() += 1;
        let distinct: BTreeSet<Kind> = r.failures.iter().map(|f| f.kind).collect();
        for k in distinct {
            *kinds.entry(k).or_default() += 1;
        }
    }
    let count = |f: &dyn Fn(&CaseResult) -> bool| results.iter().filter(|r| f(r)).count();
    let ran = count(&|r| !r.skipped);
    let fs = count(&|r| r.what.contains("file system"));
    format!(
        "cases {} (skipped {}, file-system cases {fs}), wall {:.1} s, {:.1} cases/s\n\
         info ok {}, info error {}; render ok {}, render error {}\n\
         failing cases {}; cases per failure kind {kinds:?}\nper format {formats:?}\n",
        results.len(),
        results.len() - ran,
        wall.as_secs_f64(),
        results.len() as f64 / wall.as_secs_f64().max(1e-9),
        count(&|r| r.info_ok),
        count(&|r| !r.skipped && !r.info_ok),
        count(&|r| r.render_ok == Some(true)),
        count(&|r| r.render_ok == Some(false)),
        count(&|r| !r.failures.is_empty()),
    )
}

/// Runs `count` cases of `base` (after checking the seeds), prints the summary, and fails
/// listing the failures if there are any.
fn run_and_check(base: u64, count: usize) {
    let mut seeds = seeds::all();
    // VOLUX_MUTATION_FORMATS=dicom,nrrd: only the seeds whose format starts so.
    if let Ok(only) = std::env::var("VOLUX_MUTATION_FORMATS") {
        seeds.retain(|s| only.split(',').any(|p| s.format.starts_with(p.trim())));
    }
    check_seeds(&seeds);
    let start = Instant::now();
    let results = run_all(&seeds, base, &indices(count));
    eprintln!(
        "mutation run, seed {base}:\n{}",
        summary(&results, start.elapsed())
    );
    let failing = results.iter().filter(|r| !r.failures.is_empty()).count();
    assert!(
        failing == 0,
        "{failing} of {} mutated inputs fail:\n{}",
        results.len(),
        failure_report(&results, base, 8)
    );
}

/// A few hundred mutated inputs of a fixed seed: no crash, hang, malformed error or partial
/// output.
#[test]
fn mutation_suite() {
    run_and_check(SUITE_SEED, SUITE_CASES);
}

/// The long run: `VOLUX_MUTATION_CASES` cases (default 20000) of `VOLUX_MUTATION_SEED`
/// (default the suite's seed).
#[test]
#[ignore = "long: thousands of mutated inputs (VOLUX_MUTATION_CASES, VOLUX_MUTATION_SEED)"]
fn mutation_long_run() {
    let env = |k: &str| std::env::var(k).ok().and_then(|v| v.parse().ok());
    let base = env("VOLUX_MUTATION_SEED").unwrap_or(SUITE_SEED);
    let count = env("VOLUX_MUTATION_CASES").map_or(20_000, |c: u64| c as usize);
    run_and_check(base, count);
}

/// The same index and seed give the same case; the fixed seed covers every format and
/// every file-system case.
#[test]
fn cases_are_deterministic_and_cover_the_formats() {
    let seeds = seeds::all();
    let a = make_case(&seeds, 1, 42);
    let b = make_case(&seeds, 1, 42);
    assert_eq!(a.mutation.files, b.mutation.files);
    assert_eq!((a.format, a.mutation.what), (b.format, b.mutation.what));
    let cases: Vec<Case> = (0..2000)
        .map(|i| make_case(&seeds, SUITE_SEED, i))
        .collect();
    let formats: BTreeSet<&str> = cases.iter().map(|c| c.format).collect();
    assert_eq!(formats.len(), seeds.len());
    let fs: BTreeSet<FsCase> = cases
        .iter()
        .filter_map(|c| c.mutation.fs.as_ref().map(|f| f.0))
        .collect();
    assert_eq!(fs.len(), 6, "{fs:?}");
}
