//! The one check every command's paths go through before any work: [`Plan`].
//!
//! A command lists every file it will write (`--output`, `--plot`, derived charts, the files
//! of a study's `--out` directory) and every file it reads (the scene file, `--external`
//! files); [`Plan::check`] then checks each output ([`super::check_output_path`],
//! [`super::check_output_dir`], the length of its name) and compares all of them after
//! resolving them ([`super::resolve`]: `..` also through directories that do not exist yet,
//! symlinks, relative paths), so that no output replaces another or an input.

use super::{bad_output, check_output_dir, check_output_path, is_special, resolve};
use crate::error::Result;
use std::path::{Path, PathBuf};

/// Every path a command writes or reads, checked together by [`Plan::check`].
#[derive(Debug, Default)]
pub struct Plan {
    outputs: Vec<(String, PathBuf)>,
    dirs: Vec<(String, PathBuf)>,
    inputs: Vec<(String, PathBuf)>,
    charts: Vec<(String, PathBuf)>,
}

impl Plan {
    /// An empty plan.
    pub fn new() -> Self {
        Self::default()
    }

    /// An output file; `role` names it in messages (`--output`, `the n chart`).
    pub fn output(&mut self, role: impl Into<String>, path: &Path) -> &mut Self {
        self.outputs.push((role.into(), path.to_path_buf()));
        self
    }

    /// An optional output file ([`Plan::output`] when given).
    pub fn output_opt(&mut self, role: &str, path: Option<&Path>) -> &mut Self {
        if let Some(p) = path {
            self.output(role, p);
        }
        self
    }

    /// An SVG chart the command writes (`--plot`): an output whose name must end in `.svg`
    /// (the charts are SVG only; `--plot x.png` would write SVG into a `.png`).
    pub fn chart(&mut self, role: impl Into<String>, path: &Path) -> &mut Self {
        let role = role.into();
        self.charts.push((role.clone(), path.to_path_buf()));
        self.output(role, path)
    }

    /// An optional chart ([`Plan::chart`] when given).
    pub fn chart_opt(&mut self, role: &str, path: Option<&Path>) -> &mut Self {
        if let Some(p) = path {
            self.chart(role, p);
        }
        self
    }

    /// An output directory (`role`, e.g. `--out`) and the names of the files the command
    /// writes into it, each an output compared with every other path.
    pub fn output_dir<S: AsRef<str>>(&mut self, role: &str, dir: &Path, files: &[S]) -> &mut Self {
        self.dirs.push((role.to_string(), dir.to_path_buf()));
        for f in files {
            let name = f.as_ref();
            self.outputs
                .push((format!("{role} file {name}"), dir.join(name)));
        }
        self
    }

    /// An input file (`role`, e.g. `--external`): no output may be it.
    pub fn input(&mut self, role: impl Into<String>, path: &Path) -> &mut Self {
        self.inputs.push((role.into(), path.to_path_buf()));
        self
    }

    /// The scene argument: an input when it names a file rather than a built-in scene (a
    /// built-in name wins over a file of the same name, as in [`crate::scene::Scene::load`]).
    pub fn scene(&mut self, name_or_path: &str) -> &mut Self {
        let builtin = crate::scene::Scene::builtin_names().contains(&name_or_path);
        let path = Path::new(name_or_path);
        if !builtin && path.is_file() {
            self.input("scene file", path);
        }
        self
    }

    /// Check every output (usable, its name short enough, in a usable directory), that once
    /// resolved no two outputs are the same file and no output is an input, and that every
    /// chart is named `.svg`.
    pub fn check(&self) -> Result<()> {
        for (_, dir) in &self.dirs {
            check_output_dir(dir)?;
        }
        for (_, path) in &self.outputs {
            check_output_path(path)?;
        }
        self.ensure_distinct()?;
        for (role, path) in &self.charts {
            let svg = path
                .extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("svg"));
            if !svg && !is_special(path) {
                return Err(bad_output(
                    path,
                    format!("{role} writes an SVG chart; give the file the extension .svg"),
                ));
            }
        }
        Ok(())
    }

    /// Only the comparison of [`Plan::check`]: no two outputs, and no output and input, are
    /// the same file once resolved (devices such as `/dev/null` are exempt).
    pub fn ensure_distinct(&self) -> Result<()> {
        let resolved: Vec<PathBuf> = self.outputs.iter().map(|(_, p)| resolve(p)).collect();
        let inputs: Vec<PathBuf> = self.inputs.iter().map(|(_, p)| resolve(p)).collect();
        for (i, (role, path)) in self.outputs.iter().enumerate() {
            if is_special(path) {
                continue;
            }
            for (j, (other, _)) in self.outputs.iter().enumerate().skip(i + 1) {
                if resolved[i] == resolved[j] {
                    return Err(bad_output(
                        path,
                        format!(
                            "{role} and {other} name the same file ({}); give them different \
                             paths",
                            resolved[i].display()
                        ),
                    ));
                }
            }
            for ((other, _), input) in self.inputs.iter().zip(&inputs) {
                if *input == resolved[i] {
                    return Err(bad_output(
                        path,
                        format!(
                            "{role} is the {other} read by this command ({}); writing it \
                             would destroy the input",
                            input.display()
                        ),
                    ));
                }
            }
        }
        Ok(())
    }
}
