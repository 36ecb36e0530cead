//! Tables for reports: named columns with an alignment and a number format, rows of text or
//! numbers, rendered as a GitHub-flavoured markdown table (padded so that it also reads as plain
//! text) and serialized into the report's JSON summary with full precision.

use serde::Serialize;

use crate::{Error, Result};

/// Horizontal alignment of a column.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Align {
    /// Flush left (text).
    Left,
    /// Flush right (numbers).
    Right,
    /// Centred.
    Center,
}

/// How a column prints its numbers in markdown (the JSON summary keeps full precision).
/// Non-finite values print as `inf`, `-inf` and `NaN` whatever the format.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum NumberFormat {
    /// A fixed number of decimals: `Fixed(2)` prints 1.23456 as `1.23`.
    Fixed(usize),
    /// Scientific notation with this many decimals: `Scientific(2)` prints 0.00123 as `1.23e-3`.
    Scientific(usize),
    /// This many significant digits, in scientific notation below 1e-4 or from 1e6 on:
    /// `Significant(3)` prints 0.012345 as `0.0123` and 12345.6 as `12346`.
    Significant(usize),
    /// Rounded to an integer.
    Integer,
}

/// One column: a header, an alignment and a number format.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Column {
    /// Header text.
    pub name: String,
    /// Alignment of the header and the cells.
    pub align: Align,
    /// Format of numeric cells.
    pub format: NumberFormat,
}

impl Column {
    /// A left-aligned column (for names); numbers in it get 4 significant digits.
    pub fn text(name: impl Into<String>) -> Self {
        Self { name: name.into(), align: Align::Left, format: NumberFormat::Significant(4) }
    }

    /// A right-aligned numeric column.
    pub fn number(name: impl Into<String>, format: NumberFormat) -> Self {
        Self { name: name.into(), align: Align::Right, format }
    }

    /// The same column with another alignment.
    pub fn align(mut self, align: Align) -> Self {
        self.align = align;
        self
    }
}

/// One table cell.
#[derive(Clone, Debug, PartialEq)]
pub enum Cell {
    /// Text, printed as given (`|` is escaped and line breaks become spaces in markdown).
    Text(String),
    /// A number, printed with its column's [`NumberFormat`].
    Number(f64),
    /// Nothing (a `null` in JSON).
    Empty,
}

impl Serialize for Cell {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Cell::Text(t) => s.serialize_str(t),
            Cell::Number(v) => crate::json::non_finite::serialize(v, s),
            Cell::Empty => s.serialize_unit(),
        }
    }
}

impl From<&str> for Cell {
    fn from(v: &str) -> Self {
        Cell::Text(v.to_owned())
    }
}
impl From<String> for Cell {
    fn from(v: String) -> Self {
        Cell::Text(v)
    }
}
impl From<f64> for Cell {
    fn from(v: f64) -> Self {
        Cell::Number(v)
    }
}
impl From<f32> for Cell {
    fn from(v: f32) -> Self {
        Cell::Number(f64::from(v))
    }
}
impl From<u32> for Cell {
    fn from(v: u32) -> Self {
        Cell::Number(f64::from(v))
    }
}
impl From<i32> for Cell {
    fn from(v: i32) -> Self {
        Cell::Number(f64::from(v))
    }
}
impl From<u64> for Cell {
    fn from(v: u64) -> Self {
        Cell::Number(v as f64)
    }
}
impl From<usize> for Cell {
    fn from(v: usize) -> Self {
        Cell::Number(v as f64)
    }
}
impl<T: Into<Cell>> From<Option<T>> for Cell {
    fn from(v: Option<T>) -> Self {
        v.map_or(Cell::Empty, Into::into)
    }
}

/// A named table. The name identifies it in the JSON summary.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Table {
    name: String,
    columns: Vec<Column>,
    rows: Vec<Vec<Cell>>,
}

impl Table {
    /// An empty table with these columns.
    pub fn new(name: impl Into<String>, columns: Vec<Column>) -> Self {
        Self { name: name.into(), columns, rows: Vec::new() }
    }

    /// Appends a row; it must have one cell per column.
    ///
    /// ```
    /// use voxlod_eval::report::{Column, NumberFormat, Table};
    /// let mut t = Table::new("errors", vec![
    ///     Column::text("method"),
    ///     Column::number("MSE", NumberFormat::Scientific(2)),
    /// ]);
    /// t.push_row(vec!["average".into(), 0.00123.into()]).unwrap();
    /// assert!(t.to_markdown().contains("| average | 1.23e-3 |"));
    /// assert!(t.push_row(vec!["too short".into()]).is_err());
    /// ```
    pub fn push_row(&mut self, cells: Vec<Cell>) -> Result<()> {
        if cells.len() != self.columns.len() {
            return Err(Error::RowLength {
                table: self.name.clone(),
                row: self.rows.len(),
                expected: self.columns.len(),
                got: cells.len(),
            });
        }
        self.rows.push(cells);
        Ok(())
    }

    /// The table's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The columns.
    pub fn columns(&self) -> &[Column] {
        &self.columns
    }

    /// The rows, one cell per column each.
    pub fn rows(&self) -> &[Vec<Cell>] {
        &self.rows
    }

    /// The cell as printed in markdown (unescaped).
    pub fn format_cell(&self, column: usize, cell: &Cell) -> String {
        match cell {
            Cell::Text(t) => t.clone(),
            Cell::Number(v) => format_number(*v, self.columns[column].format),
            Cell::Empty => String::new(),
        }
    }

    /// The table in markdown, columns padded to a common width. A table without columns renders
    /// as an empty string.
    pub fn to_markdown(&self) -> String {
        if self.columns.is_empty() {
            return String::new();
        }
        let header: Vec<String> = self.columns.iter().map(|c| escape(&c.name)).collect();
        let body: Vec<Vec<String>> = self
            .rows
            .iter()
            .map(|r| r.iter().enumerate().map(|(i, c)| escape(&self.format_cell(i, c))).collect())
            .collect();
        let widths: Vec<usize> = (0..self.columns.len())
            .map(|i| {
                let cells = body.iter().map(|r| r[i].chars().count());
                cells.chain([header[i].chars().count(), 3]).max().unwrap_or(3)
            })
            .collect();
        let line = |cells: &[String]| {
            let padded =
                cells.iter().enumerate().map(|(i, c)| pad(c, widths[i], self.columns[i].align));
            format!("| {} |\n", padded.collect::<Vec<_>>().join(" | "))
        };
        let mut out = line(&header);
        let rule = self.columns.iter().zip(&widths).map(|(c, &w)| match c.align {
            Align::Left => format!(":{}", "-".repeat(w - 1)),
            Align::Right => format!("{}:", "-".repeat(w - 1)),
            Align::Center => format!(":{}:", "-".repeat(w.saturating_sub(2).max(1))),
        });
        out += &format!("| {} |\n", rule.collect::<Vec<_>>().join(" | "));
        for row in &body {
            out += &line(row);
        }
        out
    }
}

/// Formats a number per `format`; non-finite values as `inf`, `-inf`, `NaN`.
pub fn format_number(v: f64, format: NumberFormat) -> String {
    if v.is_nan() {
        return "NaN".into();
    }
    if v.is_infinite() {
        return if v > 0.0 { "inf".into() } else { "-inf".into() };
    }
    match format {
        NumberFormat::Fixed(d) => format!("{v:.d$}"),
        NumberFormat::Scientific(d) => format!("{v:.d$e}"),
        NumberFormat::Integer => format!("{v:.0}"),
        NumberFormat::Significant(n) => {
            let n = n.max(1);
            if v == 0.0 {
                return "0".into();
            }
            let exp = v.abs().log10().floor() as i32;
            if !(-4..6).contains(&exp) {
                format!("{v:.*e}", n - 1)
            } else {
                format!("{v:.*}", (n as i32 - 1 - exp).max(0) as usize)
            }
        }
    }
}

fn escape(s: &str) -> String {
    s.replace('|', "\\|").replace(['\n', '\r'], " ")
}

fn pad(s: &str, width: usize, align: Align) -> String {
    let fill = width.saturating_sub(s.chars().count());
    match align {
        Align::Left => format!("{s}{}", " ".repeat(fill)),
        Align::Right => format!("{}{s}", " ".repeat(fill)),
        Align::Center => format!("{}{s}{}", " ".repeat(fill / 2), " ".repeat(fill - fill / 2)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn number_formats() {
        assert_eq!(format_number(1.23456, NumberFormat::Fixed(2)), "1.23");
        assert_eq!(format_number(0.00123, NumberFormat::Scientific(2)), "1.23e-3");
        assert_eq!(format_number(0.012345, NumberFormat::Significant(3)), "0.0123");
        assert_eq!(format_number(12345.6, NumberFormat::Significant(3)), "12346");
        assert_eq!(format_number(1.5e-7, NumberFormat::Significant(3)), "1.50e-7");
        assert_eq!(format_number(0.0, NumberFormat::Significant(3)), "0");
        assert_eq!(format_number(2.5, NumberFormat::Integer), "2");
        assert_eq!(format_number(f64::INFINITY, NumberFormat::Fixed(2)), "inf");
        assert_eq!(format_number(f64::NEG_INFINITY, NumberFormat::Integer), "-inf");
        assert_eq!(format_number(f64::NAN, NumberFormat::Scientific(1)), "NaN");
    }

    #[test]
    fn markdown_is_aligned_and_escaped() {
        let mut t = Table::new(
            "t",
            vec![
                Column::text("method"),
                Column::number("PSNR (dB)", NumberFormat::Fixed(1)),
                Column::text("note").align(Align::Center),
            ],
        );
        t.push_row(vec!["a|b".into(), f64::INFINITY.into(), Cell::Empty]).unwrap();
        t.push_row(vec!["averages".into(), 31.26.into(), "two\nlines".into()]).unwrap();
        let md = t.to_markdown();
        let want = "\
| method   | PSNR (dB) |   note    |
| :------- | --------: | :-------: |
| a\\|b     |       inf |           |
| averages |      31.3 | two lines |
";
        assert_eq!(md, want);
    }

    #[test]
    fn wrong_row_length_names_the_table_and_row() {
        let mut t = Table::new("errors", vec![Column::text("a"), Column::text("b")]);
        t.push_row(vec!["x".into(), Cell::from(Some(1u32))]).unwrap();
        let err = t.push_row(vec!["x".into()]).unwrap_err().to_string();
        assert!(err.contains("'errors'") && err.contains("row 1") && err.contains("2 columns"));
        assert_eq!(t.rows().len(), 1);
        assert_eq!(Table::new("empty", vec![]).to_markdown(), "");
    }

    #[test]
    fn json_keeps_full_precision_and_non_finite_values() {
        let mut t = Table::new("t", vec![Column::number("v", NumberFormat::Fixed(1))]);
        t.push_row(vec![0.123456789.into()]).unwrap();
        t.push_row(vec![f64::NAN.into()]).unwrap();
        t.push_row(vec![Cell::Empty]).unwrap();
        let rows = serde_json::to_string(t.rows()).unwrap();
        assert_eq!(rows, r#"[[0.123456789],["nan"],[null]]"#);
    }
}
