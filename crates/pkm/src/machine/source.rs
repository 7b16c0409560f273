//! Locating fields of a TOML source for error messages (file, line, column, field).

use std::ops::Range;

use toml::de::{DeTable, DeValue};

use crate::error::Error;

/// The largest magnitude of any number in a machine, tolerance or deviation file
/// (mm, deg, mm/s, mm/s^2, mm/min, counts): 1e6. A kilometre-long link, a million
/// degrees, a rate of a kilometre per second are typing errors; computing with them
/// (or with 1e300) only hangs sweeps and prints numbers that mean nothing.
pub const MAX_MAGNITUDE: f64 = 1e6;

/// A parsed TOML source that can turn a field path into a line and column.
pub struct Source<'a> {
    /// File name used in messages.
    pub file: &'a str,
    /// The raw text.
    pub text: &'a str,
    root: toml::Spanned<DeTable<'a>>,
}

/// One segment of a field path.
#[derive(Debug, Clone, PartialEq)]
pub enum Seg {
    /// A table key.
    Key(String),
    /// An array index.
    Index(usize),
}

/// Renders a path as `a.b[2].c`.
pub fn path_string(path: &[Seg]) -> String {
    let mut s = String::new();
    for seg in path {
        match seg {
            Seg::Key(k) => {
                if !s.is_empty() {
                    s.push('.');
                }
                s.push_str(k);
            }
            Seg::Index(i) => s.push_str(&format!("[{i}]")),
        }
    }
    s
}

/// Parses `a.b[2].c` into segments.
pub fn parse_path(path: &str) -> Vec<Seg> {
    let mut out = Vec::new();
    for part in path.split('.') {
        let mut rest = part;
        if let Some(i) = rest.find('[') {
            if i > 0 {
                out.push(Seg::Key(rest[..i].to_string()));
            }
            rest = &rest[i..];
            while let Some(stripped) = rest.strip_prefix('[') {
                let end = stripped.find(']').unwrap_or(stripped.len());
                if let Ok(n) = stripped[..end].parse() {
                    out.push(Seg::Index(n));
                }
                rest = stripped.get(end + 1..).unwrap_or("");
            }
        } else if !rest.is_empty() {
            out.push(Seg::Key(rest.to_string()));
        }
    }
    out
}

/// 1-based line and column of a byte offset.
pub fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let offset = offset.min(text.len());
    let before = &text[..offset];
    let line = before.matches('\n').count() + 1;
    let col = before
        .rfind('\n')
        .map(|i| before[i + 1..].chars().count() + 1)
        .unwrap_or_else(|| before.chars().count() + 1);
    (line, col)
}

impl<'a> Source<'a> {
    /// Parses the TOML syntax; a syntax error names its line and column.
    pub fn parse(file: &'a str, text: &'a str) -> Result<Self, Error> {
        match DeTable::parse(text) {
            Ok(root) => Ok(Source { file, text, root }),
            Err(e) => {
                let (line, column) = match e.span() {
                    Some(s) => {
                        let (l, c) = line_col(text, s.start);
                        (Some(l), Some(c))
                    }
                    None => (None, None),
                };
                Err(Error::MachineFile {
                    file: file.into(),
                    line,
                    column,
                    field: String::new(),
                    message: format!("invalid TOML: {}", e.message().trim()),
                })
            }
        }
    }

    /// The root table.
    pub fn root(&self) -> &DeTable<'a> {
        self.root.get_ref()
    }

    /// Span of the value at `path`, or of the deepest existing parent.
    pub fn span_of(&self, path: &[Seg]) -> Option<Range<usize>> {
        let mut span = None;
        let mut table: Option<&DeTable> = Some(self.root.get_ref());
        let mut array: Option<&[toml::Spanned<DeValue>]> = None;
        for seg in path {
            let next = match (seg, table, array) {
                (Seg::Key(k), Some(t), _) => t
                    .iter()
                    .find(|(key, _)| key.get_ref().as_ref() == k.as_str())
                    .map(|(_, v)| v),
                (Seg::Index(i), _, Some(a)) => a.get(*i),
                _ => None,
            };
            let Some(v) = next else { break };
            span = Some(v.span());
            table = None;
            array = None;
            match v.get_ref() {
                DeValue::Table(t) => table = Some(t),
                DeValue::Array(a) => array = Some(a.as_ref()),
                _ => {}
            }
        }
        span
    }

    /// Line and column of the start of a span, when there is one.
    fn locate(&self, span: Option<Range<usize>>) -> (Option<usize>, Option<usize>) {
        match span {
            Some(s) => {
                let (l, c) = line_col(self.text, s.start);
                (Some(l), Some(c))
            }
            None => (None, None),
        }
    }

    /// An error about the field at `path` with its line and column.
    pub fn error(&self, path: &[Seg], message: impl Into<String>) -> Error {
        let (line, column) = self.locate(self.span_of(path));
        Error::MachineFile {
            file: self.file.into(),
            line,
            column,
            field: path_string(path),
            message: message.into(),
        }
    }

    /// Refuses the first number anywhere in the file that is not finite (`nan`, `inf`)
    /// or whose magnitude is beyond [`MAX_MAGNITUDE`], naming its field and line.
    pub fn check_numbers(&self) -> Result<(), Error> {
        fn walk(v: &DeValue, path: &mut Vec<Seg>, found: &mut Option<(Vec<Seg>, String)>) {
            if found.is_some() {
                return;
            }
            match v {
                DeValue::Float(f) => {
                    let s = f.as_str().to_ascii_lowercase();
                    if s.contains("nan") || s.contains("inf") {
                        *found = Some((
                            path.clone(),
                            "expected a finite number, found nan or inf".into(),
                        ));
                    } else if let Ok(x) = s.replace('_', "").parse::<f64>() {
                        if !(x.abs() <= MAX_MAGNITUDE) {
                            *found = Some((path.clone(), beyond(f.as_str())));
                        }
                    }
                }
                DeValue::Integer(i) => {
                    let x = i128::from_str_radix(&i.as_str().replace('_', ""), i.radix())
                        .map(|x| x as f64)
                        .unwrap_or(f64::INFINITY);
                    if !(x.abs() <= MAX_MAGNITUDE) {
                        *found = Some((path.clone(), beyond(i.as_str())));
                    }
                }
                DeValue::Table(t) => {
                    for (k, v) in t.iter() {
                        path.push(Seg::Key(k.get_ref().to_string()));
                        walk(v.get_ref(), path, found);
                        path.pop();
                    }
                }
                DeValue::Array(a) => {
                    for (i, v) in a.iter().enumerate() {
                        path.push(Seg::Index(i));
                        walk(v.get_ref(), path, found);
                        path.pop();
                    }
                }
                _ => {}
            }
        }
        fn beyond(v: &str) -> String {
            format!(
                "expected a magnitude of at most 1e6 (mm, deg, mm/s, ...), found {v}: no \
                 machine has such a value, and pkm refuses it rather than compute with it"
            )
        }
        let mut found = None;
        for (k, v) in self.root().iter() {
            let mut path = vec![Seg::Key(k.get_ref().to_string())];
            walk(v.get_ref(), &mut path, &mut found);
        }
        match found {
            Some((p, message)) => Err(self.error(&p, message)),
            None => Ok(()),
        }
    }

    /// Deserializes the whole document into `T`; errors name the field path (from
    /// `serde_path_to_error`) and the line of the offending value.
    pub fn deserialize<T: serde::de::DeserializeOwned>(&self) -> Result<T, Error> {
        let de = toml::de::Deserializer::parse(self.text).map_err(|e| self.toml_error(&e, ""))?;
        serde_path_to_error::deserialize(de).map_err(|e| {
            let path = e.path().to_string();
            let path = if path == "." { String::new() } else { path };
            self.toml_error(e.inner(), &path)
        })
    }

    fn toml_error(&self, e: &toml::de::Error, path: &str) -> Error {
        let segs = parse_path(path);
        let span = e.span().or_else(|| self.span_of(&segs));
        let (line, column) = self.locate(span);
        Error::MachineFile {
            file: self.file.into(),
            line,
            column,
            field: path.to_string(),
            message: e.message().trim().to_string(),
        }
    }
}

/// Exactly `N` values in a file (`[x, y, z]`, `[min, max]`, the three rows of a
/// rotation): serde's fixed arrays take the first `N` of a longer list and drop the
/// rest without a word, so a fourth coordinate or a third bound would pass unnoticed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Exact<const N: usize, T = f64>(pub [T; N]);

impl<const N: usize, T: Default> Default for Exact<N, T> {
    fn default() -> Self {
        Exact(std::array::from_fn(|_| T::default()))
    }
}

impl<const N: usize, T> std::ops::Deref for Exact<N, T> {
    type Target = [T; N];
    fn deref(&self) -> &[T; N] {
        &self.0
    }
}

impl<const N: usize, T> From<Exact<N, T>> for [T; N] {
    fn from(e: Exact<N, T>) -> [T; N] {
        e.0
    }
}

impl<'de, const N: usize, T: serde::Deserialize<'de> + Default> serde::Deserialize<'de>
    for Exact<N, T>
{
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Values<const N: usize, T>(std::marker::PhantomData<T>);
        impl<'de, const N: usize, T: serde::Deserialize<'de> + Default> serde::de::Visitor<'de>
            for Values<N, T>
        {
            type Value = Exact<N, T>;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                write!(f, "an array of {N} values")
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut seq: A,
            ) -> Result<Exact<N, T>, A::Error> {
                let mut out: [T; N] = std::array::from_fn(|_| T::default());
                let mut n = 0;
                while let Some(v) = seq.next_element::<T>()? {
                    if n < N {
                        out[n] = v;
                    }
                    n += 1;
                }
                if n != N {
                    return Err(serde::de::Error::invalid_length(n, &self));
                }
                Ok(Exact(out))
            }
        }
        d.deserialize_seq(Values::<N, T>(std::marker::PhantomData))
    }
}
