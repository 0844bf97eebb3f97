//! `gvi ensemble SCENE --count N --perturb SIGMA`: many perturbed runs in parallel, one CSV
//! row per member, summary statistics, and the throughput on all threads against one.

use super::run::{SceneArgs, load_scene};
use crate::ensemble::{EnsembleOptions, perturbed_members, run_members};
use crate::error::LabError;
use crate::output::{Plan, write_file, write_output};
use clap::Args;
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Debug, Args)]
pub struct EnsembleArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Number of members.
    #[arg(long)]
    pub count: usize,
    /// Standard deviation σ of the Gaussian perturbation of every component of q0 and p0
    /// (absolute; 0 gives identical members).
    #[arg(long, allow_hyphen_values = true)]
    pub perturb: f64,
    /// Ensemble seed: the same seed gives the same CSV, byte for byte, on any number of
    /// threads.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Output CSV (default: stdout). The summary statistics go beside it as
    /// `<stem>-summary.csv`.
    #[arg(long, short)]
    pub output: Option<PathBuf>,
    /// Threads of the parallel run (default: one per core).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Members re-run on one thread to measure the speed-up (default: min(count, 4 × threads);
    /// 0 skips the measurement).
    #[arg(long)]
    pub throughput_sample: Option<usize>,
}

fn pool(threads: usize) -> Result<rayon::ThreadPool, LabError> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| LabError::InvalidArgument {
            name: "--threads".into(),
            reason: format!("cannot start {threads} threads: {e}"),
        })
}

/// `<stem>-summary.csv` beside `path`.
fn summary_path(path: &Path) -> PathBuf {
    let stem = path
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("ensemble");
    path.with_file_name(format!("{stem}-summary.csv"))
}

pub fn run_ensemble_command(args: EnsembleArgs) -> Result<(), LabError> {
    let scene = load_scene(&args.scene)?;
    let options = EnsembleOptions {
        count: args.count,
        sigma: args.perturb,
        seed: args.seed,
    };
    options.validate()?;
    let threads = match args.threads {
        Some(0) => {
            return Err(LabError::InvalidArgument {
                name: "--threads".into(),
                reason: "0 threads: need at least one".into(),
            });
        }
        Some(t) => t,
        None => std::thread::available_parallelism().map_or(1, |n| n.get()),
    };
    let summary_file = args.output.as_deref().map(summary_path);
    Plan::new()
        .output_opt("--output", args.output.as_deref())
        .output_opt("the summary", summary_file.as_deref())
        .scene(&args.scene.scene)
        .check()?;
    let system = scene.euclidean()?;
    crate::ensemble::ensure_memory(
        args.count,
        scene.initial.q.len(),
        galerkin_vi::systems::System::symmetries(system).len(),
    )?;
    let members = perturbed_members(&scene.initial.q, &scene.initial.p, &options)?;

    let pb = crate::progress::bar(members.len(), "ensemble");
    let start = Instant::now();
    let ensemble = pool(threads)?.install(|| run_members(&scene, &members, Some(&pb)))?;
    let parallel_seconds = start.elapsed().as_secs_f64();
    pb.finish_and_clear();

    write_output(args.output.as_deref(), &ensemble.to_csv())?;
    if let Some(s) = &summary_file {
        write_file(s, &ensemble.summary_csv())?;
    }
    eprintln!("{}", ensemble.to_string().trim_end());
    if let Some(s) = &summary_file {
        eprintln!("  summary written to {}", s.display());
    }
    if ensemble.completed().next().is_none() {
        // The rows (with each failure) are written; but there is no result to report.
        let first = ensemble.members.iter().find_map(|m| m.failure.clone());
        return Err(LabError::AllRunsFailed {
            runs: ensemble.members.len(),
            first: first.unwrap_or_default(),
        });
    }

    // Throughput: the first members again on one thread, in the same process. The results
    // must be identical (members do not depend on the thread that runs them).
    let sample = args
        .throughput_sample
        .unwrap_or(4 * threads)
        .min(members.len());
    let rate = members.len() as f64 / parallel_seconds;
    if sample > 0 {
        let start = Instant::now();
        let serial = pool(1)?.install(|| run_members(&scene, &members[..sample], None))?;
        let serial_rate = sample as f64 / start.elapsed().as_secs_f64();
        // Compared as CSV text, i.e. bit for bit (NaN fields compare equal).
        let parallel_csv = ensemble.to_csv();
        let identical = serial
            .to_csv()
            .lines()
            .eq(parallel_csv.lines().take(sample + 1));
        eprintln!(
            "  throughput: {rate:.3} members/s on {threads} threads, {serial_rate:.3} members/s \
             on 1 thread ({sample} members): speed-up {:.2}× (one-thread results {})",
            rate / serial_rate,
            if identical { "identical" } else { "DIFFER" }
        );
    } else {
        eprintln!("  throughput: {rate:.3} members/s on {threads} threads");
    }
    Ok(())
}
