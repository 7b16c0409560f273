//! LinuxCNC's INI files: `[SECTION]` headers, `KEY = VALUE` lines (a key may repeat:
//! `HALFILE`, `HALCMD`), whole-line comments starting with `#` or `;`.

use crate::error::{Error, Result};

/// One `KEY = VALUE` line.
#[derive(Debug, Clone, PartialEq)]
pub struct IniEntry {
    /// Section name without brackets (`KINS`).
    pub section: String,
    /// Key (`KINEMATICS`).
    pub key: String,
    /// Value, trimmed.
    pub value: String,
    /// 1-based line.
    pub line: usize,
}

/// A parsed INI file.
#[derive(Debug, Clone, PartialEq)]
pub struct Ini {
    /// The file's name, for messages.
    pub file: String,
    /// Every entry in file order.
    pub entries: Vec<IniEntry>,
}

/// Largest INI or HAL text read (bytes): a machine's configuration is a few kB.
pub const MAX_TEXT: usize = 4 << 20;

impl Ini {
    /// Parses `text` (named `file` in messages).
    pub fn parse(file: &str, text: &str) -> Result<Ini> {
        if text.len() > MAX_TEXT {
            return Err(file_error(
                file,
                None,
                "",
                format!(
                    "{} bytes is not a LinuxCNC INI file (at most {MAX_TEXT})",
                    text.len()
                ),
            ));
        }
        let mut section: Option<String> = None;
        let mut entries = Vec::new();
        for (i, raw) in text.lines().enumerate() {
            let line = raw.trim();
            if line.is_empty() || line.starts_with('#') || line.starts_with(';') {
                continue;
            }
            if let Some(rest) = line.strip_prefix('[') {
                let Some(name) = rest.strip_suffix(']') else {
                    return Err(file_error(
                        file,
                        Some(i + 1),
                        "",
                        format!("expected a section header `[NAME]`, found `{line}`"),
                    ));
                };
                section = Some(name.trim().to_string());
                continue;
            }
            let Some((k, v)) = line.split_once('=') else {
                return Err(file_error(
                    file,
                    Some(i + 1),
                    "",
                    format!("expected `KEY = VALUE`, found `{line}`"),
                ));
            };
            let Some(s) = &section else {
                return Err(file_error(
                    file,
                    Some(i + 1),
                    "",
                    "a `KEY = VALUE` line before any `[SECTION]`",
                ));
            };
            entries.push(IniEntry {
                section: s.clone(),
                key: k.trim().to_string(),
                value: v.trim().to_string(),
                line: i + 1,
            });
        }
        Ok(Ini {
            file: file.to_string(),
            entries,
        })
    }

    /// The first entry `[section] key` (LinuxCNC reads the first of repeated keys).
    pub fn get(&self, section: &str, key: &str) -> Option<&IniEntry> {
        self.entries
            .iter()
            .find(|e| e.section == section && e.key == key)
    }

    /// Every entry `[section] key`, in file order.
    pub fn all<'a>(&'a self, section: &'a str, key: &'a str) -> impl Iterator<Item = &'a IniEntry> {
        self.entries
            .iter()
            .filter(move |e| e.section == section && e.key == key)
    }

    /// `[section] key` as a number, `None` when absent; an error naming the line when
    /// it is not a finite number.
    pub fn number(&self, section: &str, key: &str) -> Result<Option<(f64, &IniEntry)>> {
        let Some(e) = self.get(section, key) else {
            return Ok(None);
        };
        match e.value.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(Some((v, e))),
            _ => Err(self.error(e, format!("expected a finite number, found `{}`", e.value))),
        }
    }

    /// An error at entry `e`.
    pub fn error(&self, e: &IniEntry, message: impl Into<String>) -> Error {
        file_error(
            &self.file,
            Some(e.line),
            &format!("[{}] {}", e.section, e.key),
            message,
        )
    }

    /// `file:line` of entry `e`, for comments saying where a value came from.
    pub fn at(&self, e: &IniEntry) -> String {
        format!("{}:{}", short(&self.file), e.line)
    }
}

/// The file name without its directories (comments stay short).
pub(crate) fn short(file: &str) -> &str {
    std::path::Path::new(file)
        .file_name()
        .and_then(|n| n.to_str())
        .unwrap_or(file)
}

pub(crate) fn file_error(
    file: &str,
    line: Option<usize>,
    field: &str,
    message: impl Into<String>,
) -> Error {
    Error::MachineFile {
        file: file.to_string(),
        line,
        column: None,
        field: field.to_string(),
        message: message.into(),
    }
}
