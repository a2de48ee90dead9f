//! Progress for long jobs on stderr: a bar with counts on a terminal, plain lines every few
//! seconds otherwise (logs, batch jobs).

use anyhow::Result;
use geltip::jobs::dataset;
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;

/// A bar of `unit`s: elapsed time, the bar, the count, then `tail` (indicatif's template
/// keys, such as `{msg}`).
pub fn bar(unit: &str, tail: &str) -> Result<ProgressBar> {
    Ok(ProgressBar::new(0).with_style(
        ProgressStyle::with_template(&format!(
            "{{elapsed_precise}} [{{bar:40}}] {{pos}}/{{len}} {unit} {tail}"
        ))?
        .progress_chars("=> "),
    ))
}

/// A progress callback for long jobs: a bar with rate and ETA on a terminal, a plain line
/// every few seconds otherwise (logs, batch jobs).
pub fn reporter(unit: &'static str) -> Result<impl FnMut(dataset::Progress)> {
    let terminal = std::io::stderr().is_terminal();
    let bar = bar(unit, "{per_sec} ETA {eta}")?;
    let start = std::time::Instant::now();
    let mut last_line = start;
    Ok(move |p: dataset::Progress| {
        if terminal {
            bar.set_length(p.total);
            bar.set_position(p.done);
            if p.done == p.total && p.total > 0 {
                bar.finish_and_clear();
            }
        } else if last_line.elapsed().as_secs() >= 5 || (p.done == p.total && p.total > 0) {
            last_line = std::time::Instant::now();
            let rate = p.done as f64 / start.elapsed().as_secs_f64().max(1e-9);
            eprintln!("{}/{} {unit} ({rate:.1}/s)", p.done, p.total);
        }
    })
}

/// A progress bar on a terminal; plain periodic lines on stderr otherwise (indicatif hides
/// itself when stderr is not a terminal, so those lines come from a thread here).
pub fn bar_or_lines(unit: &str) -> Result<ProgressBar> {
    let bar = bar(unit, "{msg}")?;
    if !std::io::stderr().is_terminal() {
        let unit = unit.to_string();
        let shown = bar.clone();
        std::thread::spawn(move || loop {
            std::thread::sleep(std::time::Duration::from_secs(5));
            if shown.is_finished() {
                break;
            }
            eprintln!(
                "{}/{} {unit}",
                shown.position(),
                shown.length().unwrap_or(0)
            );
        });
    }
    Ok(bar)
}
