//! Tables: CSV through the `csv` crate with serde rows, and Markdown tables.
//!
//! Every CSV the lab writes goes through [`csv_text`] (rows that are `#[derive(Serialize)]`
//! structs; the header is their field names) or [`csv_records`] (tables whose columns depend on
//! the system, such as `q0, q1, …`). The number formats are part of the files' contract — the
//! studies under `docs/studies/` are regenerated and compared byte for byte — so columns keep
//! the format they have always had through the `serialize_with` helpers here: [`sci`] (Rust's
//! `{:e}`, the shortest round-trip digits), [`fixed`] (a fixed number of decimals) and their
//! `Option` forms, which leave the cell empty for `None`. Free text (failure messages, parameter
//! lists) is always quoted by [`quoted`]; the other cells are names and numbers without commas,
//! so the writer itself never adds quotes ([`csv::QuoteStyle::Never`]).

use crate::error::{LabError, Result};
use serde::{Serialize, Serializer};

/// The writer all tables share: no automatic quoting (see the module documentation).
fn writer() -> csv::Writer<Vec<u8>> {
    csv::WriterBuilder::new()
        .quote_style(csv::QuoteStyle::Never)
        .from_writer(Vec::new())
}

fn finish(w: csv::Writer<Vec<u8>>) -> Result<String> {
    let bytes = w
        .into_inner()
        .map_err(|e| LabError::Serialize(e.to_string()))?;
    String::from_utf8(bytes).map_err(|e| LabError::Serialize(e.to_string()))
}

fn csv_err(e: csv::Error) -> LabError {
    LabError::Serialize(e.to_string())
}

/// CSV text of serde rows: a header of the row type's field names (written with the first row,
/// so an empty table is empty), then one line per row.
pub fn csv_text<R: Serialize>(rows: impl IntoIterator<Item = R>) -> Result<String> {
    let mut w = writer();
    for row in rows {
        w.serialize(row).map_err(csv_err)?;
    }
    finish(w)
}

/// CSV text of a header and rows of already formatted cells, for tables whose columns depend
/// on the data (one column per coordinate or body).
pub fn csv_records<I, R, C>(header: &[String], rows: I) -> Result<String>
where
    I: IntoIterator<Item = R>,
    R: IntoIterator<Item = C>,
    C: AsRef<[u8]>,
{
    let mut w = writer();
    w.write_record(header).map_err(csv_err)?;
    for row in rows {
        w.write_record(row).map_err(csv_err)?;
    }
    finish(w)
}

/// A number of a data table (`gvi run`, `gvi ensemble`, `gvi section`): Rust's shortest
/// round-trip digits, written plainly where that reads well (0, and 1e-4 ≤ |x| < 1e15:
/// `0.4`, `200`, `-0`, `0.3333333333333333`) and in exponent form otherwise (`1e-300`,
/// `6.02214076e23`). Either form reads back bit for bit (Rust's `parse::<f64>`, Python's
/// `float`, numpy). NaN is an empty cell; infinities are `inf` and `-inf`.
///
/// ```
/// use galerkin_vi_lab::table::number;
/// assert_eq!(number(0.4), "0.4");
/// assert_eq!(number(198.0), "198");
/// assert_eq!(number(1e-300), "1e-300");
/// assert_eq!(number(f64::NAN), "");
/// let third = 1.0 / 3.0;
/// assert_eq!(number(third).parse::<f64>().unwrap().to_bits(), third.to_bits());
/// ```
pub fn number(x: f64) -> String {
    let a = x.abs();
    if x.is_nan() {
        String::new()
    } else if x == 0.0 || !x.is_finite() || (1e-4..1e15).contains(&a) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// `{:e}`: Rust's shortest round-trip digits in exponent form (`1.5e-3`, `2e0`).
pub fn sci<S: Serializer>(x: &f64, s: S) -> std::result::Result<S::Ok, S::Error> {
    s.collect_str(&format_args!("{x:e}"))
}

/// [`sci`], or an empty cell for `None`.
pub fn sci_opt<S: Serializer>(x: &Option<f64>, s: S) -> std::result::Result<S::Ok, S::Error> {
    match x {
        Some(v) => sci(v, s),
        None => s.serialize_str(""),
    }
}

/// Rust's `{}` (shortest round-trip digits, no exponent: `2`, `0.125`).
pub fn plain<S: Serializer>(x: &f64, s: S) -> std::result::Result<S::Ok, S::Error> {
    s.collect_str(x)
}

/// `P` decimals (`{:.P$}`).
pub fn fixed<const P: usize, S: Serializer>(x: &f64, s: S) -> std::result::Result<S::Ok, S::Error> {
    s.collect_str(&format_args!("{x:.P$}"))
}

/// [`fixed`], or an empty cell for `None`.
pub fn fixed_opt<const P: usize, S: Serializer>(
    x: &Option<f64>,
    s: S,
) -> std::result::Result<S::Ok, S::Error> {
    match x {
        Some(v) => fixed::<P, S>(v, s),
        None => s.serialize_str(""),
    }
}

/// Free text in double quotes (a `"` inside becomes `'`), or an empty cell for `None`.
pub fn quoted<S: Serializer>(x: &Option<&str>, s: S) -> std::result::Result<S::Ok, S::Error> {
    match x {
        Some(text) => s.collect_str(&format_args!("\"{}\"", text.replace('"', "'"))),
        None => s.serialize_str(""),
    }
}

/// A Markdown table: `| a | b |`, the `|---|---|` rule, then one line per row.
pub fn markdown<I, R, C>(header: &[&str], rows: I) -> String
where
    I: IntoIterator<Item = R>,
    R: IntoIterator<Item = C>,
    C: std::fmt::Display,
{
    let mut out = line(header.iter());
    out.push('|');
    for _ in header {
        out.push_str("---|");
    }
    out.push('\n');
    for row in rows {
        out.push_str(&line(row));
    }
    out
}

fn line<C: std::fmt::Display>(cells: impl IntoIterator<Item = C>) -> String {
    let mut out = String::from("|");
    for c in cells {
        out.push_str(&format!(" {c} |"));
    }
    out.push('\n');
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Serialize)]
    struct Row<'a> {
        name: &'a str,
        count: usize,
        #[serde(serialize_with = "sci")]
        h: f64,
        #[serde(serialize_with = "sci_opt")]
        error: Option<f64>,
        #[serde(serialize_with = "fixed::<3, _>")]
        factor: f64,
        #[serde(serialize_with = "quoted")]
        failure: Option<&'a str>,
    }

    #[test]
    fn csv_keeps_the_formats() {
        let rows = [
            Row {
                name: "chebyshev",
                count: 3,
                h: 0.5,
                error: Some(1.25e-12),
                factor: 2.0 / 3.0,
                failure: None,
            },
            Row {
                name: "legendre",
                count: 40,
                h: 2.0,
                error: None,
                factor: 1.0,
                failure: Some("Newton \"failed\" at step 0, t = 0"),
            },
        ];
        assert_eq!(
            csv_text(&rows).unwrap(),
            "name,count,h,error,factor,failure\n\
             chebyshev,3,5e-1,1.25e-12,0.667,\n\
             legendre,40,2e0,,1.000,\"Newton 'failed' at step 0, t = 0\"\n"
        );
        let header = ["t".to_string(), "q0".to_string()];
        let text = csv_records(&header, [["1e0", "2e0"], ["3e0", ""]]).unwrap();
        assert_eq!(text, "t,q0\n1e0,2e0\n3e0,\n");
    }

    /// Every value of a data table reads back bit for bit, in both forms (plain and exponent),
    /// at the edges of the plain range and beyond it.
    #[test]
    fn numbers_read_back_bit_for_bit() {
        let values = [
            0.4,
            200.0,
            198.0,
            1.0 / 3.0,
            -2.0 / 3.0,
            0.0,
            -0.0,
            1e-300,
            -1e-300,
            5e-324,
            f64::MIN_POSITIVE,
            f64::MAX,
            f64::MIN,
            1e15,
            1e15 - 1.0,
            9.999999999999999e14,
            1e-4,
            9.999999999999999e-5,
            6.02214076e23,
            std::f64::consts::PI * 1e7,
            0.1 + 0.2,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ];
        for x in values {
            let text = number(x);
            let back: f64 = text.parse().unwrap();
            assert_eq!(back.to_bits(), x.to_bits(), "{x:e} written as {text}");
            assert!(text.len() <= 24, "{text} is too long");
        }
        assert_eq!(number(-0.0), "-0");
        assert_eq!(number(0.4), "0.4");
        assert_eq!(number(1e15), "1e15");
        assert_eq!(number(123456.5), "123456.5");
        assert_eq!(number(f64::NAN), "");
    }

    #[test]
    fn markdown_table() {
        let t = markdown(&["a", "b"], [vec!["1".to_string(), String::new()]]);
        assert_eq!(t, "| a | b |\n|---|---|\n| 1 |  |\n");
    }
}
