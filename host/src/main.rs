//! The `cargo host` command line: parses arguments and calls the library.
use anyhow::Result;
use clap::{Parser, Subcommand};
use inkstep_host::{bench, plan::PlanOptions};

#[derive(Parser)]
#[command(name = "inkstep-host", about = "inkstep's PC tool")]
struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
}

#[derive(Subcommand)]
enum Cmd {
    /// Pen-up travel of natural, greedy, inkstep and vpype orders on a text.
    PlanBench {
        #[arg(default_value = bench::DEFAULT_TEXT)]
        text: String,
        /// vpype command to compare with ("" to skip).
        #[arg(long, default_value = "vpype")]
        vpype: String,
    },
}

fn main() -> Result<()> {
    match Cli::parse().cmd {
        Cmd::PlanBench { text, vpype } => {
            let rows = bench::run(&text, &PlanOptions::default(), (!vpype.is_empty()).then_some(vpype.as_str()))?;
            print!("{}", bench::table(&rows));
        }
    }
    Ok(())
}
