//! Progress bars for long sweeps: on stderr, and only when stderr is a terminal.
//!
//! Studies that sweep many runs (`refine`, `compare-bases`, `work-precision`, `stability`,
//! `tolerance-study`, `solver-scaling`, `ensemble`) advance one bar per finished run; nothing is
//! drawn when stderr is redirected, so logs and CI output stay clean.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;

/// A progress bar that is silent unless stderr is a terminal.
pub fn bar(len: usize, label: &str) -> ProgressBar {
    let pb = ProgressBar::with_draw_target(Some(len as u64), ProgressDrawTarget::stderr());
    if !std::io::stderr().is_terminal() {
        pb.set_draw_target(ProgressDrawTarget::hidden());
    }
    if let Ok(style) =
        ProgressStyle::with_template("{msg:>16} [{bar:40}] {pos}/{len} ({elapsed}, eta {eta})")
    {
        pb.set_style(style.progress_chars("=> "));
    }
    pb.set_message(label.to_string());
    pb
}
