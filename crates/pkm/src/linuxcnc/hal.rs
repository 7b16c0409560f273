//! The parameters a LinuxCNC configuration gives its kinematics module in HAL: `setp
//! NAME VALUE` (or `NAME = VALUE`), and `sets SIGNAL VALUE` on a signal that `net`
//! joins to the parameter. A value may be an INI reference `[SECTION]KEY`. Other
//! commands (`loadrt`, `addf`, `net` of pins to pins...) do not set geometry and are
//! skipped.

use std::collections::BTreeMap;

use super::ini::{file_error, short, Ini};
use crate::error::Result;

/// A parameter's value and where it was set.
#[derive(Debug, Clone, PartialEq)]
pub struct HalValue {
    /// The value, in the configuration's units.
    pub value: f64,
    /// `file:line` of the `setp` (or `sets`) that gave it.
    pub at: String,
    /// File and line, for errors.
    pub file: String,
    /// 1-based line.
    pub line: usize,
}

/// Every parameter set, every signal's value and the signals joined to each pin.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Hal {
    /// `setp` values by parameter name (the last one wins, as in HAL).
    pub setp: BTreeMap<String, HalValue>,
    /// `sets` values by signal.
    pub sets: BTreeMap<String, HalValue>,
    /// The signal each pin is on (`net SIGNAL pin pin...`).
    pub nets: BTreeMap<String, (String, String)>,
}

/// The number word `w` (or the INI entry it references) of line `line` of `file`.
fn number(w: &str, ini: &Ini, file: &str, line: usize) -> Result<f64> {
    let v = resolve(w, ini).ok_or_else(|| {
        file_error(
            file,
            Some(line),
            "",
            format!("INI reference `{w}` names no entry of {}", short(&ini.file)),
        )
    })?;
    match v.parse::<f64>() {
        Ok(x) if x.is_finite() => Ok(x),
        _ => Err(file_error(
            file,
            Some(line),
            "",
            format!("expected a finite number, found `{v}`"),
        )),
    }
}

impl Hal {
    /// Reads one HAL file (or the INI's `HALCMD` lines) into the collection; INI
    /// references resolve against `ini`.
    pub fn read(&mut self, file: &str, text: &str, first_line: usize, ini: &Ini) -> Result<()> {
        if text.len() > super::ini::MAX_TEXT {
            return Err(file_error(
                file,
                None,
                "",
                format!("{} bytes is not a HAL file", text.len()),
            ));
        }
        for (i, raw) in text.lines().enumerate() {
            let line = first_line + i;
            let code = raw.split('#').next().unwrap_or("").trim();
            if code.is_empty() {
                continue;
            }
            self.read_line(file, line, code, ini)?;
        }
        Ok(())
    }

    /// Reads the statement `code` of line `line` of `file`: `setp`, `NAME = VALUE`,
    /// `sets` or `net`; other statements are skipped.
    fn read_line(&mut self, file: &str, line: usize, code: &str, ini: &Ini) -> Result<()> {
        let words: Vec<&str> = code.split_whitespace().collect();
        let value = |w: &str| number(w, ini, file, line);
        let record = |v: f64| HalValue {
            value: v,
            at: format!("{}:{line}", short(file)),
            file: file.to_string(),
            line,
        };
        match words.as_slice() {
            ["setp", name, v] => {
                let x = value(v)?;
                self.setp.insert(name.to_string(), record(x));
            }
            [name, "=", v] => {
                let x = value(v)?;
                self.setp.insert(name.to_string(), record(x));
            }
            ["sets", signal, v] => {
                let x = value(v)?;
                self.sets.insert(signal.to_string(), record(x));
            }
            ["net", signal, pins @ ..] => {
                for p in pins.iter().filter(|p| !matches!(**p, "<=" | "=>" | "<=>")) {
                    self.nets.insert(
                        p.to_string(),
                        (signal.to_string(), format!("{}:{line}", short(file))),
                    );
                }
            }
            ["setp", ..] | ["sets", ..] => {
                return Err(file_error(
                    file,
                    Some(line),
                    "",
                    format!("expected `{} NAME VALUE`, found `{code}`", words[0]),
                ));
            }
            _ => {}
        }
        Ok(())
    }

    /// The value a parameter (or input pin) has: its `setp`, or the `sets` value of
    /// the signal `net` joins it to. `Err` with the signal's name and where it is
    /// joined when the pin follows a signal nothing sets (it changes at run time, such
    /// as `motion.tooloffset.z`).
    pub fn value(&self, name: &str) -> std::result::Result<Option<HalValue>, (String, String)> {
        if let Some((sig, at)) = self.nets.get(name) {
            return match self.sets.get(sig) {
                Some(v) => Ok(Some(v.clone())),
                None => match self.setp.get(name) {
                    Some(v) => Ok(Some(v.clone())),
                    None => Err((sig.clone(), at.clone())),
                },
            };
        }
        Ok(self.setp.get(name).cloned())
    }
}

/// A HAL word, or the INI value it references (`[SECTION]KEY`).
fn resolve(word: &str, ini: &Ini) -> Option<String> {
    let Some(rest) = word.strip_prefix('[') else {
        return Some(word.to_string());
    };
    let (section, key) = rest.split_once(']')?;
    ini.get(section, key).map(|e| e.value.clone())
}
