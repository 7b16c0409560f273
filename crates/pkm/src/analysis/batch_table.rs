//! The batch file of `pkm ik --input` / `pkm fk --input`: a CSV table of numbers whose
//! header names the values (`X,Y,Z,A,B,C`, `X_mm,...`, or the actuator names).
//!
//! ```text
//! # poses from the CAM system        <- comment lines start with `#`
//! X,Y,Z,A,B,C
//! 0, 0, -290, 0, 0, 0
//! 10,5,-300,2,0,0
//! ```
//!
//! Header names match case-insensitively, with or without a unit suffix (`_mm`,
//! `_deg`, `[mm]`, ` (deg)`); cells are trimmed and must be finite numbers; blank
//! lines are skipped. Errors name the file, the line and the column.

use super::batch::MAX_BATCH;
use crate::error::{Error, Result};

/// A batch file read: its header as written, and the rows with their 1-based lines.
///
/// # Examples
///
/// See [`parse_batch_table`].
#[derive(Debug, Clone, PartialEq)]
pub struct BatchTable {
    /// Header names as written.
    pub header: Vec<String>,
    /// (line, values) per data row, in file order.
    pub rows: Vec<(u64, Vec<f64>)>,
}

/// A header name without its unit suffix, lowercase, for matching.
fn canonical(name: &str) -> String {
    let n = name.trim().to_ascii_lowercase();
    for suf in ["_mm", "_deg", "[mm]", "[deg]", " (mm)", " (deg)"] {
        if let Some(s) = n.strip_suffix(suf) {
            return s.trim().to_string();
        }
    }
    n
}

fn error(file: &str, line: u64, field: &str, message: String) -> Error {
    Error::MachineFile {
        file: file.into(),
        line: Some(line as usize),
        column: None,
        field: field.into(),
        message,
    }
}

/// Parses `text` (the contents of `file`) as a batch table whose header names one of
/// the `accepted` column lists; at most [`MAX_BATCH`] rows.
///
/// # Examples
///
/// ```
/// use pkm::analysis::batch_table::parse_batch_table;
/// let names = |s: &str| s.split(',').map(String::from).collect::<Vec<_>>();
/// let accepted = [names("x,y,z,a,b,c"), names("l1,l2,l3,l4,l5,l6")];
/// let text = "# poses from the CAM system\nX_mm,Y_mm,Z_mm,A_deg,B_deg,C_deg\n\
///             0, 0, 508, 0, 0, 0\n\n10,5,500,2,0,0\n";
/// let t = parse_batch_table(text, "poses.csv", &accepted).unwrap();
/// assert_eq!(t.header[0], "X_mm"); // as written
/// // Rows with their lines: the blank line is skipped.
/// assert_eq!(t.rows.len(), 2);
/// assert_eq!(t.rows[0], (3, vec![0.0, 0.0, 508.0, 0.0, 0.0, 0.0]));
/// assert_eq!(t.rows[1], (5, vec![10.0, 5.0, 500.0, 2.0, 0.0, 0.0]));
/// // A header naming other columns, or a cell that is not a number, is refused.
/// assert!(parse_batch_table("U,V\n1,2\n", "poses.csv", &accepted).is_err());
/// let e = parse_batch_table("X,Y,Z,A,B,C\n1,2,3,4,5,six\n", "poses.csv", &accepted).unwrap_err();
/// assert!(e.to_string().contains("six"));
/// ```
pub fn parse_batch_table(text: &str, file: &str, accepted: &[Vec<String>]) -> Result<BatchTable> {
    let mut rdr = csv::ReaderBuilder::new()
        .has_headers(true)
        .trim(csv::Trim::All)
        .comment(Some(b'#'))
        .flexible(true)
        .from_reader(text.as_bytes());
    let header: Vec<String> = rdr
        .headers()
        .map_err(|e| error(file, 1, "", format!("cannot read the header row: {e}")))?
        .iter()
        .map(str::to_string)
        .collect();
    // Lines by byte offset: the reader's own line count skips comment lines.
    let mut lines = LineCounter::new(text);
    let header_line = lines.clone().at(0);
    check_header(&header, accepted, file, header_line)?;
    let mut rows = Vec::new();
    for rec in rdr.records() {
        let rec = rec.map_err(|e| {
            let line = e.position().map_or(0, |p| lines.clone().at(p.byte()));
            error(file, line, "", format!("malformed CSV: {e}"))
        })?;
        if rec.len() == 1 && rec[0].is_empty() {
            // A line of spaces: blank.
            continue;
        }
        let line = rec.position().map_or(0, |p| lines.at(p.byte()));
        if rows.len() >= MAX_BATCH {
            return Err(error(
                file,
                line,
                "",
                format!("more than {MAX_BATCH} rows: split the batch"),
            ));
        }
        if rec.len() != header.len() {
            return Err(error(
                file,
                line,
                "",
                format!("expected {} values, found {}", header.len(), rec.len()),
            ));
        }
        let vals = row_values(&rec, &header, file, line)?;
        rows.push((line, vals));
    }
    Ok(BatchTable { header, rows })
}

/// Checks `header` names the columns of one of the `accepted` headers.
fn check_header(
    header: &[String],
    accepted: &[Vec<String>],
    file: &str,
    header_line: u64,
) -> Result<()> {
    let got: Vec<String> = header.iter().map(|h| canonical(h)).collect();
    let ok = accepted.iter().any(|a| {
        a.len() == got.len()
            && a.iter()
                .zip(&got)
                .all(|(x, y)| x.to_ascii_lowercase() == *y)
    });
    if !ok {
        let expected = accepted
            .iter()
            .map(|a| format!("`{}`", a.join(",")))
            .collect::<Vec<_>>()
            .join(" or ");
        return Err(error(
            file,
            header_line,
            "",
            format!(
                "header `{}` does not name the expected columns; expected {expected}",
                header.join(",")
            ),
        ));
    }
    Ok(())
}

/// The values of record `rec` at `line`, each a finite number.
fn row_values(
    rec: &csv::StringRecord,
    header: &[String],
    file: &str,
    line: u64,
) -> Result<Vec<f64>> {
    let mut vals = Vec::with_capacity(rec.len());
    for (i, cell) in rec.iter().enumerate() {
        match cell.parse::<f64>() {
            Ok(v) if v.is_finite() => vals.push(v),
            _ => {
                return Err(error(
                    file,
                    line,
                    &header[i],
                    format!("expected a finite number, found `{cell}`"),
                ))
            }
        }
    }
    Ok(vals)
}

/// The 1-based lines of records by the byte offsets the reader reports, asked in
/// increasing order: newlines counted once.
#[derive(Clone)]
struct LineCounter<'a> {
    text: &'a [u8],
    /// Offset counted up to, and the line there.
    at: usize,
    line: u64,
}

impl<'a> LineCounter<'a> {
    fn new(text: &'a str) -> Self {
        LineCounter {
            text: text.as_bytes(),
            at: 0,
            line: 1,
        }
    }

    /// The line of the record the reader started reading at `offset`: the reader
    /// begins a record where the previous one ended, before the blank and comment
    /// lines it skips, so those are passed over here.
    fn at(&mut self, offset: u64) -> u64 {
        let to = (offset as usize).min(self.text.len());
        // Lines that end before `offset` (the reader may point into a `\r\n`).
        while self.at < to {
            let (end, next) = line_end(self.text, self.at);
            if end >= to {
                break;
            }
            self.at = next;
            self.line += 1;
        }
        loop {
            let (end, next) = line_end(self.text, self.at);
            let content = self.text[self.at..end].trim_ascii();
            if next > end && (content.is_empty() || content.starts_with(b"#")) {
                self.at = next;
                self.line += 1;
            } else {
                return self.line;
            }
        }
    }
}

/// The end of the line starting at `from` and the start of the next one: a line ends
/// at `\n`, `\r\n` or a lone `\r`, as the CSV reader's records do.
fn line_end(text: &[u8], from: usize) -> (usize, usize) {
    match text[from..].iter().position(|b| *b == b'\n' || *b == b'\r') {
        None => (text.len(), text.len()),
        Some(k) => {
            let e = from + k;
            let crlf = text[e] == b'\r' && text.get(e + 1) == Some(&b'\n');
            (e, e + 1 + usize::from(crlf))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn xyz() -> Vec<Vec<String>> {
        vec![["X", "Y", "Z"].map(String::from).to_vec()]
    }

    #[test]
    fn rows_keep_their_lines_and_units_and_comments_are_skipped() {
        let t = parse_batch_table(
            "# from CAM\nX_mm, y ,Z [mm]\n1,2,3\n\n# gap\n -4 , 5e-3, 6\n",
            "p.csv",
            &xyz(),
        )
        .unwrap();
        assert_eq!(t.header, ["X_mm", "y", "Z [mm]"]);
        assert_eq!(
            t.rows,
            vec![(3, vec![1.0, 2.0, 3.0]), (6, vec![-4.0, 5e-3, 6.0])]
        );
    }

    #[test]
    fn errors_name_the_file_line_and_column() {
        let e = |text: &str| {
            parse_batch_table(text, "p.csv", &xyz())
                .unwrap_err()
                .to_string()
        };
        assert_eq!(
            e("X,Y,Z\n1,2,3\n1,abc,3\n"),
            "p.csv:3: field `Y`: expected a finite number, found `abc`"
        );
        assert_eq!(
            e("X,Y,Z\n1,2,3\n1,NaN,3\n"),
            "p.csv:3: field `Y`: expected a finite number, found `NaN`"
        );
        // Blank and comment lines before the row count (the reader's own count skips
        // comments), and Windows line ends.
        assert!(e("X,Y,Z\n1,2,3\n\n# note\n  \n1,abc,3\n").starts_with("p.csv:6: field `Y`"));
        let crlf = e("X,Y,Z\r\n1,2,3\r\n# c\r\n1,abc,3\r\n");
        assert!(crlf.starts_with("p.csv:4: field `Y`"), "{crlf}");
        // Old Mac line ends (a lone carriage return) end lines too.
        assert!(e("X,Y,Z\r1,2,3\r\r1,abc,3\r").starts_with("p.csv:4: field `Y`"));
        assert!(e("X,Y,Z\n1,2\n").starts_with("p.csv:2: expected 3 values, found 2"));
        assert!(e("A,B\n1,2\n").starts_with("p.csv:1: header `A,B` does not name"));
        assert!(e("# c\nA,B\n1,2\n").starts_with("p.csv:2: header"));
    }
}
