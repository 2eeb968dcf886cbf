//! Measured curves: a CSV file with a header line of column names, then one line of numbers
//! per point. Lines starting with `#` are comments (the data's source goes there); blank
//! lines are skipped; values are separated by commas.

use std::path::Path;

use crate::case::CaseError;

/// A measured CSV table.
#[derive(Debug, Clone)]
pub struct Table {
    /// Column names from the header.
    pub names: Vec<String>,
    /// Rows of values, with their line numbers (1-based) in the file.
    pub rows: Vec<(usize, Vec<f64>)>,
}

/// Largest measured CSV file read: 16 MiB.
pub const MAX_DATA_FILE_BYTES: u64 = 16 << 20;

impl Table {
    /// Reads the CSV file `path`; errors name the file and the line.
    pub fn read(path: &Path) -> Result<Self, CaseError> {
        let data = crate::input::read_limited(path, MAX_DATA_FILE_BYTES, "data file")
            .map_err(|m| CaseError::new(path.display().to_string(), m))?;
        let text = String::from_utf8(data)
            .map_err(|_| CaseError::new(path.display().to_string(), "data file is not UTF-8 text"))?;
        Self::parse(&text).map_err(|(line, message)| CaseError::new(format!("{}:line {line}", path.display()), message))
    }

    /// Parses CSV text; an error is the line number and what is wrong.
    pub fn parse(text: &str) -> Result<Self, (usize, String)> {
        let mut names: Option<Vec<String>> = None;
        let mut rows = Vec::new();
        for (k, line) in text.lines().enumerate() {
            let line_no = k + 1;
            let line = line.trim();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            let fields: Vec<&str> = line.split(',').map(str::trim).collect();
            let Some(names) = &names else {
                if let Some(empty) = fields.iter().position(|f| f.is_empty()) {
                    return Err((line_no, format!("header: column {} has no name", empty + 1)));
                }
                names = Some(fields.iter().map(|s| s.to_string()).collect());
                continue;
            };
            if fields.len() != names.len() {
                return Err((line_no, format!("{} values for {} columns", fields.len(), names.len())));
            }
            let row = fields
                .iter()
                .zip(names)
                .map(|(f, name)| {
                    f.parse::<f64>()
                        .ok()
                        .filter(|v| v.is_finite())
                        .ok_or_else(|| (line_no, format!("column `{name}`: `{f}` is not a finite number")))
                })
                .collect::<Result<Vec<f64>, _>>()?;
            rows.push((line_no, row));
        }
        let names = names.ok_or((1, "no header line of column names".to_string()))?;
        if rows.is_empty() {
            return Err((text.lines().count().max(1), "no rows of values after the header".into()));
        }
        Ok(Self { names, rows })
    }

    /// The index of column `name`.
    pub fn column(&self, name: &str) -> Option<usize> {
        self.names.iter().position(|n| n == name)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn comments_header_rows_and_errors_with_their_line() {
        let t = Table::parse("# source: synthetic\n\nea, q\n0, 0\n1.5,20\n").unwrap();
        assert_eq!(t.names, ["ea", "q"]);
        assert_eq!(t.rows, vec![(4, vec![0.0, 0.0]), (5, vec![1.5, 20.0])]);
        assert_eq!(Table::parse("a,b\n1,2\n3\n").unwrap_err(), (3, "1 values for 2 columns".to_string()));
        assert_eq!(Table::parse("a,b\n1,x\n").unwrap_err(), (2, "column `b`: `x` is not a finite number".to_string()));
        assert_eq!(Table::parse("a,b\n1,NaN\n").unwrap_err().0, 2);
        assert_eq!(Table::parse("# only\n").unwrap_err().1, "no header line of column names");
        assert_eq!(Table::parse("a,,c\n").unwrap_err(), (1, "header: column 2 has no name".to_string()));
    }
}
