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
//!
//! A table with more columns than the values, such as the one `pkm ik --output` or
//! `pkm fk --output` writes (the input's columns, the results, `reachable`, the
//! violated limits), is read too: the columns named by the values are taken and the
//! others left unread, so each command reads what the other writes. A row whose
//! taken cells are all empty (an earlier batch's row without a solution) is kept,
//! without values, so that row `k` of the output is row `k` of the input.

use super::batch::MAX_BATCH;
use crate::error::{Error, Result};

/// A batch file read: the names of the columns taken, as written, and the rows with
/// their 1-based lines.
///
/// # Examples
///
/// See [`parse_batch_table`].
#[derive(Debug, Clone, PartialEq)]
pub struct BatchTable {
    /// Names of the columns taken as written (the whole header when it names just
    /// the values).
    pub header: Vec<String>,
    /// (line, values of the columns taken) per data row, in file order; the values
    /// are empty where every cell taken is empty.
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
    let taken = select_columns(&header, accepted)
        .map_err(|message| error(file, header_line, "", message))?;
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
        let vals = row_values(&rec, &taken, &header)
            .map_err(|(field, message)| error(file, line, field, message))?;
        rows.push((line, vals));
    }
    let header = taken.iter().map(|&k| header[k].clone()).collect();
    Ok(BatchTable { header, rows })
}

/// The columns of `header` to read: all of them when the header names one of the
/// `accepted` lists; else those naming the longest list whose every name the header
/// holds once, the other columns left unread; or why none fits. A header holding
/// some names of a longer list but not all (`X,Y,Z,A,B,CC`) is refused rather than
/// read as the shorter one.
fn select_columns(
    header: &[String],
    accepted: &[Vec<String>],
) -> std::result::Result<Vec<usize>, String> {
    let got: Vec<String> = header.iter().map(|h| canonical(h)).collect();
    let lower = |a: &[String]| a.iter().map(|x| x.to_ascii_lowercase()).collect::<Vec<_>>();
    if accepted.iter().any(|a| lower(a) == got) {
        return Ok((0..header.len()).collect());
    }
    let expected = accepted
        .iter()
        .map(|a| format!("`{}`", a.join(",")))
        .collect::<Vec<_>>()
        .join(" or ");
    let refused = |why: String| format!("header `{}` {why}; expected {expected}", header.join(","));
    // Longest first, each with its names as the caller spells them.
    let mut lists: Vec<(&Vec<String>, Vec<String>)> =
        accepted.iter().map(|a| (a, lower(a))).collect();
    lists.sort_by_key(|(a, _)| std::cmp::Reverse(a.len()));
    for (i, (_, names)) in lists.iter().enumerate() {
        let mut taken = Vec::with_capacity(names.len());
        for (n, name) in names.iter().enumerate() {
            let mut at = got.iter().enumerate().filter(|(_, g)| *g == name);
            match (at.next(), at.next()) {
                (Some((k, _)), None) => taken.push(k),
                (Some(_), Some(_)) => {
                    let name = &lists[i].0[n];
                    return Err(refused(format!("names the column `{name}` more than once")));
                }
                (None, _) => break,
            }
        }
        if taken.len() < names.len() {
            continue;
        }
        // A longer list partly named: a misspelt or missing column, not a shorter list.
        for (spelt, longer) in &lists[..i] {
            let (named, missing): (Vec<usize>, Vec<usize>) = (0..longer.len())
                .filter(|&k| !names.contains(&longer[k]))
                .partition(|&k| got.contains(&longer[k]));
            if !named.is_empty() {
                let join = |ks: &[usize]| {
                    ks.iter()
                        .map(|&k| spelt[k].as_str())
                        .collect::<Vec<_>>()
                        .join(",")
                };
                return Err(refused(format!(
                    "names `{}` of `{}` but not `{}`",
                    join(&named),
                    spelt.join(","),
                    join(&missing)
                )));
            }
        }
        return Ok(taken);
    }
    Err(refused("does not name the expected columns".into()))
}

/// The values of the `taken` cells of a record: finite numbers, or none where every
/// taken cell is empty; else the field and what was wrong.
fn row_values<'h>(
    rec: &csv::StringRecord,
    taken: &[usize],
    header: &'h [String],
) -> std::result::Result<Vec<f64>, (&'h str, String)> {
    if taken.len() < rec.len() && taken.iter().all(|&k| rec[k].is_empty()) {
        return Ok(Vec::new());
    }
    let mut vals = Vec::with_capacity(taken.len());
    for &k in taken {
        let cell = &rec[k];
        match cell.parse::<f64>() {
            Ok(v) if v.is_finite() => vals.push(v),
            _ => {
                return Err((
                    &header[k],
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

    fn pose_lists() -> Vec<Vec<String>> {
        vec![
            ["X", "Y", "Z", "A", "B", "C"].map(String::from).to_vec(),
            ["X", "Y", "Z"].map(String::from).to_vec(),
        ]
    }

    #[test]
    fn another_commands_table_is_read_by_the_columns_it_names() {
        // What `pkm ik --output` writes: the input, the actuators (empty without a
        // solution), reachable, the violations (text with commas, quoted).
        let ik_out = "X,Y,Z,A,B,C,L1_mm,L2_mm,reachable,violations\n\
                      0,0,508,0,0,0,755.5,755.6,true,\n\
                      0,0,908,0,0,0,1066.4,1066.5,false,\"strut 0, above\"\n\
                      0,0,9000,0,0,0,,,false,no solution\n";
        let legs = vec![vec!["L1".to_string(), "L2".to_string()]];
        let t = parse_batch_table(ik_out, "q.csv", &legs).unwrap();
        assert_eq!(t.header, ["L1_mm", "L2_mm"]);
        assert_eq!(
            t.rows,
            vec![
                (2, vec![755.5, 755.6]),
                (3, vec![1066.4, 1066.5]),
                // Kept, without values: row k of the output is row k of the input.
                (4, vec![]),
            ]
        );
        // The poses, read back by the longest list the header holds.
        let t = parse_batch_table(ik_out, "q.csv", &pose_lists()).unwrap();
        assert_eq!(t.header, ["X", "Y", "Z", "A", "B", "C"]);
        assert_eq!(t.rows[2], (4, vec![0.0, 0.0, 9000.0, 0.0, 0.0, 0.0]));
        // Columns in another order are taken in the list's order.
        let t = parse_batch_table("Z,note,X,Y\n3,a,1,2\n", "p.csv", &xyz()).unwrap();
        assert_eq!(
            (t.header, t.rows),
            (
                vec!["X".into(), "Y".into(), "Z".into()],
                vec![(2, vec![1.0, 2.0, 3.0])]
            )
        );
    }

    #[test]
    fn a_header_naming_part_of_a_longer_list_or_a_name_twice_is_refused() {
        let e = |text: &str, lists: &[Vec<String>]| {
            parse_batch_table(text, "p.csv", lists)
                .unwrap_err()
                .to_string()
        };
        // A misspelt C is not read as a position-only table.
        assert_eq!(
            e("X,Y,Z,A,B,CC\n1,2,3,4,5,6\n", &pose_lists()),
            "p.csv:1: header `X,Y,Z,A,B,CC` names `A,B` of `X,Y,Z,A,B,C` but not `C`; \
             expected `X,Y,Z,A,B,C` or `X,Y,Z`"
        );
        assert!(
            e("X,Y,Z,X_mm,t\n1,2,3,4,5\n", &xyz()).contains("names the column `X` more than once")
        );
        // A table of just the values has no row without values: empty cells are errors.
        assert!(
            e("X,Y,Z\n,,\n", &xyz()).starts_with("p.csv:2: field `X`: expected a finite number")
        );
        // Partly empty taken cells are errors in a wider table too.
        assert!(e("X,Y,Z,t\n1,,3,a\n", &xyz()).starts_with("p.csv:2: field `Y`"));
    }
}
