//! The `geltip` command line: parses the arguments, runs the command (one function each in
//! [`cli`]) and prints its error on one line.

mod cli;

use clap::Parser;
use cli::{Cli, Command};

fn main() {
    // Frames are megabytes each, a new pair per frame: keep freed memory instead of
    // page-faulting it back in every frame (see geltip::memory).
    geltip::memory::keep_freed_memory();
    // Mesa's Vulkan loader prints "error: XDG_RUNTIME_DIR is invalid" on headless machines
    // while probing for a Wayland display geltip never uses; point it somewhere harmless.
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        std::env::set_var("XDG_RUNTIME_DIR", std::env::temp_dir());
    }
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    let done = match Cli::parse().command {
        Command::Sensors => cli::sensor::sensors(),
        Command::Unproject(args) => cli::sensor::unproject(args),
        Command::Project(args) => cli::sensor::project(args),
        Command::Render(args) => cli::render::render(args),
        Command::Localise(args) => cli::localise::localise(args),
        Command::Experiment(args) => cli::jobs::experiment(args),
        Command::Dataset(args) => cli::dataset::dataset(args),
        Command::Evaluate(args) => cli::evaluate::evaluate(args),
        Command::Calibrate(args) => cli::calibrate::calibrate(args),
        Command::Imprint(args) => cli::imprint::imprint(args),
        Command::Preview(args) => cli::jobs::preview(args),
        Command::Stability(args) => cli::jobs::stability(args),
        Command::Tradeoff(args) => cli::jobs::tradeoff(args),
        Command::Objects(args) => cli::jobs::objects(args),
    };
    // Library errors carry their causes in their one line; the chain adds only the
    // binary's own context.
    if let Err(e) = done {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}
