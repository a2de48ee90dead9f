//! The fuzz targets of `tests/fuzz.rs`, run longer: `cargo bench --bench fuzz -- --cases N`
//! (default 20 000 a target; `--only NAME` runs one target). Prints a table of each
//! parser's cases, how many were refused and accepted, its slowest case and failures, and
//! exits 1 if any case failed (a failing case's input is saved; its number reproduces it).

#[path = "../tests/fuzz/mod.rs"]
mod fuzz;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let value = |flag: &str| {
        args.iter()
            .position(|a| a == flag)
            .and_then(|i| args.get(i + 1))
            .cloned()
    };
    let cases: usize = value("--cases")
        .and_then(|n| n.parse().ok())
        .unwrap_or(20_000);
    let only = value("--only");
    println!("{}", fuzz::header());
    let mut failed = Vec::new();
    for target in fuzz::targets::all() {
        if only.as_deref().is_some_and(|o| o != target.name) {
            continue;
        }
        let r = fuzz::run(target, cases);
        println!("{}", fuzz::row(&r));
        if !r.failures.is_empty() {
            failed.push(fuzz::describe(&r));
        }
    }
    for f in &failed {
        println!("\n{f}");
    }
    if !failed.is_empty() {
        std::process::exit(1);
    }
}
