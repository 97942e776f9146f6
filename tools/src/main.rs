//! `spu`: assemble, disassemble, run, profile and render on simulated SPUs.
//!
//! Each subcommand lives in its own module so that the commands can grow independently.

#[macro_use]
mod exit;

mod cmd_animate;
mod cmd_ar;
mod cmd_as;
mod cmd_bench;
mod cmd_dis;
mod cmd_ld;
mod cmd_paper;
mod cmd_prof;
mod cmd_render;
mod cmd_run;
mod cmd_sched;
mod cmd_timing;
mod frame_views;
mod heatmap;
mod job_budget;
mod options;
mod outputs;
mod paper_beyond;
mod paper_data;
mod paper_figure;
mod paper_jobs;
mod paper_next;
mod paper_report;
mod paper_tables;
mod peak_memory;
mod png;
mod prepared;
mod render_options;
mod trace;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "spu",
    version,
    about = "Cell BE SPU toolchain and cycle-level simulator"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Assemble GNU-as SPU assembly into an SPU ELF or a flat image.
    As(cmd_as::Args),
    /// Disassemble an SPU ELF or a raw image, in GNU objdump's format.
    Dis(cmd_dis::Args),
    /// Link relocatable SPU objects into an executable.
    Ld(cmd_ld::Args),
    /// Build or list a static library of SPU objects (GNU ar's rcs and t).
    Ar(cmd_ar::Args),
    /// Run a program on one simulated SPU and print how it stopped.
    Run(cmd_run::Args),
    /// Run a program with the timing model and print an annotated profile.
    Prof(cmd_prof::Args),
    /// Static timing of straight-line code per basic block, like IBM's spu_timing.
    Timing(cmd_timing::Args),
    /// Ray-trace a scene on 1 to 64 simulated SPEs.
    Render(cmd_render::Args),
    /// List-schedule straight-line code into dual-issue pairs (`.sched` blocks).
    Sched(cmd_sched::Args),
    /// Measure simulator speed: simulated instructions per host second.
    Bench(cmd_bench::Args),
    /// Re-run the paper's experiments and report its numbers next to ours.
    Paper(cmd_paper::Args),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    exit::on_interrupt_remove_temporaries();
    let result = match cli.command {
        Command::As(args) => cmd_as::run(args),
        Command::Dis(args) => cmd_dis::run(args),
        Command::Ld(args) => cmd_ld::run(args),
        Command::Ar(args) => cmd_ar::run(args),
        Command::Run(args) => cmd_run::run(args),
        Command::Prof(args) => cmd_prof::run(args),
        Command::Timing(args) => cmd_timing::run(args),
        Command::Render(args) => cmd_render::run(args),
        Command::Bench(args) => cmd_bench::run(args),
        Command::Sched(args) => cmd_sched::run(args),
        Command::Paper(args) => cmd_paper::run(args),
    };
    match result {
        Ok(code) => code,
        Err(error) => {
            if let Some(message) = &error.message {
                eprintln!("spu: {message}");
            }
            error.status.into()
        }
    }
}
