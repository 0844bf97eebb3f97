//! Rows of external peers (REBOUND, …) in the study's CSV schema, read for
//! [`WorkPrecisionStudy::merge_external`](super::WorkPrecisionStudy::merge_external).

use super::WorkPoint;
use crate::error::LabError;
use crate::error::Result;
use std::path::Path;

/// The columns of the study's CSV that an external file must have (any order); optional
/// `quad_points` (Galerkin quadrature points, read) and `external` (ignored: every row read
/// is external) columns may be present too.
pub const EXTERNAL_COLUMNS: [&str; 10] = [
    "method",
    "parameters",
    "h",
    "n",
    "tolerance",
    "error",
    "seconds",
    "force_evaluations",
    "pareto",
    "failure",
];

/// Split one CSV line: fields separated by commas, a field in double quotes may hold commas,
/// and `""` inside quotes is one quote.
fn split_csv_line(line: &str) -> std::result::Result<Vec<String>, String> {
    let mut fields = Vec::new();
    let mut field = String::new();
    let mut chars = line.chars().peekable();
    let mut quoted = false;
    let mut at_start = true;
    while let Some(c) = chars.next() {
        if quoted {
            if c == '"' {
                if chars.peek() == Some(&'"') {
                    field.push('"');
                    chars.next();
                } else {
                    quoted = false;
                    if !matches!(chars.peek(), None | Some(',')) {
                        return Err("text after a closing quote".into());
                    }
                }
            } else {
                field.push(c);
            }
        } else if c == ',' {
            fields.push(std::mem::take(&mut field));
            at_start = true;
            continue;
        } else if c == '"' && at_start {
            quoted = true;
        } else if c == '"' {
            return Err("a quote inside an unquoted field".into());
        } else {
            field.push(c);
        }
        at_start = false;
    }
    if quoted {
        return Err("unterminated quoted field".into());
    }
    fields.push(field);
    Ok(fields)
}

/// A failed row skipped by [`read_external`]: a row with a failure and no finite time (the
/// study's own CSV writes `NaN` seconds for a run that failed before it was timed).
#[derive(Debug, Clone, PartialEq)]
pub struct SkippedRow {
    /// 1-based line in the file.
    pub line: usize,
    /// Method family.
    pub method: String,
    /// Its parameters.
    pub parameters: String,
    /// The row's failure text.
    pub failure: String,
}

impl std::fmt::Display for SkippedRow {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "line {}: skipped the failed row {} ({}): {}",
            self.line, self.method, self.parameters, self.failure
        )
    }
}

/// The rows of an external file: those merged, and the failed rows skipped.
#[derive(Debug, Clone)]
pub struct ExternalRows {
    /// The rows read, every one marked `external`.
    pub points: Vec<WorkPoint>,
    /// Failed rows without a finite time, skipped (the caller prints a note for each).
    pub skipped: Vec<SkippedRow>,
}

/// [`read_external`] without the notes: the rows read (failed rows without a finite time are
/// dropped silently).
pub fn read_external_csv(path: &Path) -> Result<Vec<WorkPoint>> {
    read_external(path).map(|rows| rows.points)
}

/// Read an external work–precision CSV (the study's schema, see [`EXTERNAL_COLUMNS`]): a
/// header line, then one row per configuration. Blank lines and lines starting with `#`
/// (provenance comments) are skipped. Every row is marked `external`; its `pareto` value is
/// parsed but recomputed on merging. A row with a failure whose `seconds` is not a finite
/// number (`NaN`, as the study's own CSV writes for a run that failed; or empty) is skipped
/// and listed in [`ExternalRows::skipped`], so that a study's own CSV reads back whole.
///
/// Errors: [`LabError::ExternalFile`] if the file cannot be read; [`LabError::ExternalCsv`]
/// naming the file and the 1-based line for a missing, unknown or duplicate column, a row with
/// the wrong number of fields, an empty method, or a malformed number (`h`, `tolerance`,
/// `seconds` must be finite, `seconds` ≥ 0; `error` must be finite and ≥ 0 unless the row has
/// a failure; `n` and `force_evaluations` are non-negative integers; `pareto` is `true` or
/// `false`).
pub fn read_external(path: &Path) -> Result<ExternalRows> {
    let text = std::fs::read_to_string(path).map_err(|source| LabError::ExternalFile {
        path: path.to_path_buf(),
        source,
    })?;
    let bad = |line: usize, reason: String| LabError::ExternalCsv {
        path: path.to_path_buf(),
        line,
        reason,
    };
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim_end_matches('\r')))
        .filter(|(_, l)| !l.trim().is_empty() && !l.starts_with('#'));
    let (header_line, header) = lines
        .next()
        .ok_or_else(|| bad(1, "empty file: no header line".into()))?;
    let names = split_csv_line(header).map_err(|r| bad(header_line, r))?;
    let mut column = [usize::MAX; 10];
    let mut quad_points_column = None;
    for (i, name) in names.iter().enumerate() {
        let name = name.trim();
        match EXTERNAL_COLUMNS.iter().position(|c| *c == name) {
            Some(c) if column[c] != usize::MAX => {
                return Err(bad(header_line, format!("duplicate column '{name}'")));
            }
            Some(c) => column[c] = i,
            None if name == "external" => {}
            None if name == "quad_points" && quad_points_column.is_some() => {
                return Err(bad(header_line, format!("duplicate column '{name}'")));
            }
            None if name == "quad_points" => quad_points_column = Some(i),
            None => {
                return Err(bad(
                    header_line,
                    format!(
                        "unknown column '{name}' (expected {})",
                        EXTERNAL_COLUMNS.join(",")
                    ),
                ));
            }
        }
    }
    if let Some(c) = column.iter().position(|&i| i == usize::MAX) {
        return Err(bad(
            header_line,
            format!(
                "missing column '{}' (expected {})",
                EXTERNAL_COLUMNS[c],
                EXTERNAL_COLUMNS.join(",")
            ),
        ));
    }
    let mut points = Vec::new();
    let mut skipped = Vec::new();
    for (line, row) in lines {
        let fields = split_csv_line(row).map_err(|r| bad(line, r))?;
        if fields.len() != names.len() {
            return Err(bad(
                line,
                format!("{} fields, the header has {}", fields.len(), names.len()),
            ));
        }
        let get = |c: usize| fields[column[c]].trim();
        let number = |c: usize| -> Result<Option<f64>> {
            let v = get(c);
            if v.is_empty() {
                return Ok(None);
            }
            v.parse::<f64>().map(Some).map_err(|_| {
                bad(
                    line,
                    format!("{}: malformed number '{v}'", EXTERNAL_COLUMNS[c]),
                )
            })
        };
        let finite = |c: usize, x: Option<f64>| -> Result<Option<f64>> {
            match x {
                Some(v) if !v.is_finite() => Err(bad(
                    line,
                    format!("{}: non-finite number '{}'", EXTERNAL_COLUMNS[c], get(c)),
                )),
                _ => Ok(x),
            }
        };
        let integer = |c: usize| -> Result<Option<usize>> {
            let v = get(c);
            if v.is_empty() {
                return Ok(None);
            }
            v.parse::<usize>().map(Some).map_err(|_| {
                bad(
                    line,
                    format!("{}: not a non-negative integer '{v}'", EXTERNAL_COLUMNS[c]),
                )
            })
        };
        let quad_points = match quad_points_column.map(|i| fields[i].trim()) {
            None | Some("") => None,
            Some(v) => Some(v.parse::<usize>().map_err(|_| {
                bad(
                    line,
                    format!("quad_points: not a non-negative integer '{v}'"),
                )
            })?),
        };
        let method = get(0).to_string();
        if method.is_empty() {
            return Err(bad(line, "method: empty".into()));
        }
        let failure = Some(get(9).to_string()).filter(|f| !f.is_empty());
        if let Some(failure) = &failure {
            // A failed run has no time to compare: skip it with a note, but only if its
            // seconds cell is a number that is not finite, or empty (a malformed cell stays an
            // error).
            if number(6)?.is_none_or(|s| !s.is_finite()) {
                skipped.push(SkippedRow {
                    line,
                    method,
                    parameters: get(1).to_string(),
                    failure: failure.clone(),
                });
                continue;
            }
        }
        let h = finite(2, number(2)?)?;
        let tolerance = finite(4, number(4)?)?;
        let error = number(5)?.ok_or_else(|| bad(line, "error: missing".into()))?;
        let error = if failure.is_none() {
            finite(5, Some(error))?.unwrap_or(error)
        } else {
            error
        };
        if error < 0.0 || error.is_nan() {
            return Err(bad(line, format!("error: must be ≥ 0, got '{}'", get(5))));
        }
        let seconds = finite(6, number(6)?)?.ok_or_else(|| bad(line, "seconds: missing".into()))?;
        if seconds < 0.0 {
            return Err(bad(line, format!("seconds: must be ≥ 0, got {seconds}")));
        }
        let pareto = match get(8) {
            "true" => true,
            "false" | "" => false,
            v => {
                return Err(bad(
                    line,
                    format!("pareto: expected true or false, got '{v}'"),
                ));
            }
        };
        points.push(WorkPoint {
            method,
            parameters: get(1).to_string(),
            h,
            n: integer(3)?,
            quad_points,
            tolerance,
            error,
            seconds,
            force_evaluations: integer(7)?.unwrap_or(0),
            failure,
            pareto,
            external: true,
        });
    }
    Ok(ExternalRows { points, skipped })
}
