//! # galerkin-vi lab
//!
//! The application around the [`galerkin_vi`] library: the `gvi` command-line tool and the
//! measured studies it regenerates. The library integrates; this crate reads scenes (TOML files
//! and the built-in ones), runs them, sweeps methods, fits rates, draws charts and writes
//! reports. It owns the application dependencies (clap, plotters, indicatif, toml, serde_json,
//! the DOP853 peer), so that a user of the library pulls in none of them.
//!
//! - [`scene`]: the scene file format and the built-in scenes; `Scene::build` turns a scene into
//!   the system, the validated initial state and the method, once.
//! - [`run`]: one run of a scene (`gvi run`), streamed or in memory, with monitors.
//! - [`studies`]: refinement, basis comparison, work–precision, stability, tolerance and scaling
//!   studies, and the paper's experiments.
//! - [`nbody_report`], [`periodic`], [`run::rigid_body`]: N-body accuracy reports, periodic orbits of
//!   scenes, rigid-body runs.
//! - [`ensemble`]: perturbed members of a scene in parallel (`gvi ensemble`).
//! - [`energy`]: the one scale (T₀ + |V₀|) of every relative energy error the commands report.
//! - [`fit`], [`plot`], [`output`], [`progress`], [`memory`]: rate fits, SVG charts, atomic
//!   file output (every path checked by one [`output::Plan`]), progress bars and the memory
//!   estimates every command makes before its work.
//! - [`cli`]: the `gvi` command line.
//!
//! The guide (docs/guide/ in the repository) documents every command and study with the command
//! that regenerates its numbers; docs/DESIGN.md describes the architecture.

#![warn(missing_docs)]
#![allow(clippy::needless_range_loop)]

pub mod cli;
mod distance;
#[cfg(feature = "dop853")]
pub mod dop853;
pub mod energy;
pub mod ensemble;
pub mod error;
pub mod fit;
pub mod interrupt;
pub mod memory;
pub mod names;
pub mod nbody_report;
pub mod nbody_scene;
pub mod output;
pub mod periodic;
pub mod plot;
pub mod progress;
pub mod ring;
pub mod run;
pub mod scene;
pub mod section;
pub mod studies;
pub mod table;

pub use error::{GviError, Result, ensure_finite, ensure_len};
