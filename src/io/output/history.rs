//! The CSV load history: one row per converged step, rewritten whole after every row.

use std::path::{Path, PathBuf};

use super::{content_error, write_atomic};
use crate::{Error, Result};

/// A CSV history file with fixed columns. Every [`History::push_row`] rewrites the whole file
/// atomically, so the file on disk is always complete.
#[derive(Clone, Debug)]
pub struct History {
    path: PathBuf,
    columns: Vec<String>,
    rows: Vec<Vec<f64>>,
}

/// Quotes a CSV field if it needs it (RFC 4180).
fn quote(field: &str) -> String {
    if field.contains([',', '"', '\n', '\r']) || field.trim() != field {
        format!("\"{}\"", field.replace('"', "\"\""))
    } else {
        field.to_string()
    }
}

impl History {
    /// A history of `columns` to be written at `path`. Nothing is written until
    /// [`History::write`] or the first [`History::push_row`].
    pub fn new(
        path: impl Into<PathBuf>,
        columns: impl IntoIterator<Item = impl Into<String>>,
    ) -> History {
        History {
            path: path.into(),
            columns: columns.into_iter().map(Into::into).collect(),
            rows: Vec::new(),
        }
    }

    /// Appends a row (one value per column, all finite) and rewrites the file. On error the
    /// row is not kept and the file keeps its previous contents.
    pub fn push_row(&mut self, row: Vec<f64>) -> Result<()> {
        if row.len() != self.columns.len() {
            return Err(content_error(
                &self.path,
                format!(
                    "history row has {} values for {} columns",
                    row.len(),
                    self.columns.len()
                ),
            ));
        }
        if let Some(i) = row.iter().position(|v| !v.is_finite()) {
            return Err(content_error(
                &self.path,
                format!(
                    "history column '{}' is not finite ({}) in row {}",
                    self.columns[i],
                    row[i],
                    self.rows.len()
                ),
            ));
        }
        self.rows.push(row);
        if let Err(e) = self.write() {
            self.rows.pop();
            return Err(e);
        }
        Ok(())
    }

    /// Writes the file as it stands (the header alone if there are no rows yet).
    pub fn write(&self) -> Result<()> {
        write_atomic(&self.path, self.to_csv().as_bytes())
    }

    /// The CSV text of the history.
    pub fn to_csv(&self) -> String {
        let mut out = self
            .columns
            .iter()
            .map(|c| quote(c))
            .collect::<Vec<_>>()
            .join(",");
        out.push('\n');
        for row in &self.rows {
            let line: Vec<String> = row.iter().map(|&v| format_number(v)).collect();
            out.push_str(&line.join(","));
            out.push('\n');
        }
        out
    }

    /// The rows so far.
    pub fn rows(&self) -> &[Vec<f64>] {
        &self.rows
    }

    /// Replaces the rows (a restart: those of its checkpoint), without writing the file.
    pub fn restore_rows(&mut self, rows: Vec<Vec<f64>>) {
        self.rows = rows;
    }

    /// The column names.
    pub fn columns(&self) -> &[String] {
        &self.columns
    }

    /// The file written.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

/// Splits CSV text into records of fields (RFC 4180 quoting; `\n` or `\r\n` line ends; blank
/// lines skipped).
fn records(text: &str) -> std::result::Result<Vec<(usize, Vec<String>)>, String> {
    let mut out = Vec::new();
    let mut fields = Vec::new();
    let mut field = String::new();
    let mut quoted = false;
    let mut line = 1;
    let mut start_line = 1;
    let mut chars = text.chars().peekable();
    while let Some(c) = chars.next() {
        if quoted {
            match c {
                '"' if chars.peek() == Some(&'"') => {
                    chars.next();
                    field.push('"');
                }
                '"' => quoted = false,
                _ => {
                    if c == '\n' {
                        line += 1;
                    }
                    field.push(c);
                }
            }
            continue;
        }
        match c {
            '"' if field.is_empty() => quoted = true,
            ',' => fields.push(std::mem::take(&mut field)),
            '\r' if chars.peek() == Some(&'\n') => {}
            '\n' => {
                fields.push(std::mem::take(&mut field));
                if !(fields.len() == 1 && fields[0].is_empty()) {
                    out.push((start_line, std::mem::take(&mut fields)));
                }
                fields.clear();
                line += 1;
                start_line = line;
            }
            _ => field.push(c),
        }
    }
    if quoted {
        return Err(format!("unterminated quote starting on line {start_line}"));
    }
    if !field.is_empty() || !fields.is_empty() {
        fields.push(field);
        out.push((start_line, fields));
    }
    Ok(out)
}

/// Reads a CSV file written by [`History`]: the column names and the rows.
pub fn read_csv(path: &Path) -> Result<(Vec<String>, Vec<Vec<f64>>)> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let mut recs = records(&text)
        .map_err(|m| content_error(path, m))?
        .into_iter();
    let Some((_, columns)) = recs.next() else {
        return Err(content_error(path, "empty CSV file, no header"));
    };
    let mut rows = Vec::new();
    for (line, rec) in recs {
        if rec.len() != columns.len() {
            return Err(content_error(
                path,
                format!(
                    "line {line} has {} fields for {} columns",
                    rec.len(),
                    columns.len()
                ),
            ));
        }
        let row = rec
            .iter()
            .zip(&columns)
            .map(|(f, c)| {
                f.trim().parse::<f64>().map_err(|_| {
                    content_error(
                        path,
                        format!("line {line}, column '{c}': not a number: {f:?}"),
                    )
                })
            })
            .collect::<Result<Vec<f64>>>()?;
        rows.push(row);
    }
    Ok((columns, rows))
}

/// Integers as integers (`3`), everything else in scientific notation with the shortest digits
/// that round-trip (`-5.551115123125783e-17`, `1.5e0`), so columns stay readable.
fn format_number(v: f64) -> String {
    if v.fract() == 0.0 && v.abs() < 1e15 && !(v == 0.0 && v.is_sign_negative()) {
        format!("{}", v as i64)
    } else {
        format!("{v:e}")
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_util::Scratch;
    use super::*;

    #[test]
    fn csv_round_trip_after_every_row() {
        let dir = Scratch::new("csv");
        let p = dir.path("history.csv");
        let mut h = History::new(&p, ["step", "load", "reaction, z", "say \"hi\""]);
        h.write().unwrap();
        let (cols, rows) = read_csv(&p).unwrap();
        assert_eq!(cols, h.columns());
        assert!(rows.is_empty());
        let data = [
            vec![1.0, 0.1, -1.0 / 3.0, 1e-300],
            vec![2.0, 0.2, 6.02214076e23, -0.0],
            vec![3.0, 0.30000000000000004, f64::MAX, f64::MIN_POSITIVE],
        ];
        for (i, row) in data.iter().enumerate() {
            h.push_row(row.clone()).unwrap();
            let (cols, rows) = read_csv(&p).unwrap();
            assert_eq!(cols[2], "reaction, z");
            assert_eq!(cols[3], "say \"hi\"");
            assert_eq!(rows, &data[..=i]);
            for (a, b) in rows.iter().flatten().zip(data.iter().flatten()) {
                assert_eq!(a.to_bits(), b.to_bits());
            }
        }
        assert_eq!(h.rows(), &data[..]);
        assert_eq!(dir.listing(), vec!["history.csv".to_string()]);
        assert!(std::fs::read_to_string(&p)
            .unwrap()
            .lines()
            .nth(1)
            .unwrap()
            .starts_with("1,1e-1,"));
    }

    #[test]
    fn bad_rows_rejected_and_not_kept() {
        let dir = Scratch::new("csv-bad");
        let p = dir.path("h.csv");
        let mut h = History::new(&p, vec!["a".to_string(), "b".to_string()]);
        h.push_row(vec![1.0, 2.0]).unwrap();
        assert!(h.push_row(vec![1.0]).is_err());
        let msg = h.push_row(vec![1.0, f64::NAN]).unwrap_err().to_string();
        assert!(msg.contains("'b'"), "{msg}");
        assert_eq!(h.rows().len(), 1);
        assert_eq!(read_csv(&p).unwrap().1, vec![vec![1.0, 2.0]]);
    }

    #[test]
    fn read_csv_errors() {
        let dir = Scratch::new("csv-read");
        let p = dir.path("x.csv");
        std::fs::write(&p, "a,b\n1,2\n3\n").unwrap();
        assert!(read_csv(&p).unwrap_err().to_string().contains("line 3"));
        std::fs::write(&p, "a,b\r\n1,zz\r\n").unwrap();
        assert!(read_csv(&p).unwrap_err().to_string().contains("'b'"));
        std::fs::write(&p, "a,b\r\n1,2\r\n\r\n").unwrap();
        assert_eq!(read_csv(&p).unwrap().1, vec![vec![1.0, 2.0]]);
        assert!(matches!(
            read_csv(&dir.path("none.csv")),
            Err(Error::Io { .. })
        ));
    }
}
