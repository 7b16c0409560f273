//! A LinuxCNC tool table (`.tbl`): one tool per line, `T<n> P<pocket> Z<length>
//! D<diameter> ;comment`, words in any order, `;` starting the comment. pkm reads the
//! tool number and its length along the tool axis (`Z`, in the table's unit, mm here);
//! the other words are accepted and ignored.

use std::collections::BTreeMap;

use crate::error::{Error, Result};

/// The most tools a table may list.
pub const MAX_TOOLS: usize = 100_000;

/// Tool lengths (mm) by tool number from the text of a tool table named `file`.
pub fn parse_tool_table(file: &str, text: &str) -> Result<BTreeMap<u32, f64>> {
    let bad = |line: usize, message: String| Error::InvalidInput {
        what: format!("{file}:{line}"),
        message,
    };
    let mut out = BTreeMap::new();
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let code = raw.split(';').next().unwrap_or("").trim();
        if code.is_empty() {
            continue;
        }
        let (mut t, mut z) = (None, None);
        for w in code.split_whitespace() {
            let mut chars = w.chars();
            let letter = chars.next().unwrap_or(' ').to_ascii_uppercase();
            let rest = chars.as_str();
            match letter {
                'T' => {
                    t =
                        Some(rest.parse::<u32>().map_err(|_| {
                            bad(line, format!("`{w}`: expected a tool number after T"))
                        })?)
                }
                'Z' => {
                    let v = rest
                        .parse::<f64>()
                        .ok()
                        .filter(|v| v.is_finite() && v.abs() <= crate::machine::MAX_MAGNITUDE)
                        .ok_or_else(|| {
                            bad(line, format!("`{w}`: expected a length (mm) after Z"))
                        })?;
                    z = Some(v);
                }
                'P' | 'D' | 'X' | 'Y' | 'A' | 'B' | 'C' | 'U' | 'V' | 'W' | 'I' | 'J' | 'Q' => {}
                _ => return Err(bad(line, format!("`{w}`: not a tool table word"))),
            }
        }
        let t = t.ok_or_else(|| bad(line, "a tool line needs T (the tool number)".into()))?;
        if out.len() >= MAX_TOOLS {
            return Err(bad(line, format!("more than {MAX_TOOLS} tools")));
        }
        if out.insert(t, z.unwrap_or(0.0)).is_some() {
            return Err(bad(line, format!("tool {t} is listed twice")));
        }
    }
    Ok(out)
}
