//! Walking Kratos' JSON files so that no key goes unnoticed.
//!
//! A [`Section`] is one JSON object at a JSON path (`solver_settings.time_stepping`); every
//! key the importer reads is marked, and [`Section::finish`] reports every key that was not
//! read as ignored, one line each with its file and JSON path.

use std::cell::RefCell;

use serde_json::{Map, Value};

/// Why a Kratos case folder could not be imported: one line naming the file (and line or
/// JSON path) and the problem.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct ImportError(pub String);

impl From<super::mdpa::MdpaError> for ImportError {
    fn from(e: super::mdpa::MdpaError) -> Self {
        ImportError(e.to_string())
    }
}

/// Parses JSON text, the error naming `file`, line and column.
pub fn parse_json(text: &str, file: &str) -> Result<Value, ImportError> {
    serde_json::from_str(text).map_err(|e| ImportError(format!("{file}:{}: invalid JSON: {e}", e.line())))
}

/// One JSON object of a file at a JSON path, remembering which keys were read.
pub struct Section<'a> {
    map: &'a Map<String, Value>,
    path: String,
    file: &'a str,
    used: RefCell<Vec<String>>,
}

impl<'a> Section<'a> {
    /// The top-level object of `file`.
    pub fn root(v: &'a Value, file: &'a str) -> Result<Self, ImportError> {
        let map = v.as_object().ok_or_else(|| ImportError(format!("{file}: the top level must be a JSON object")))?;
        Ok(Section { map, path: String::new(), file, used: RefCell::new(Vec::new()) })
    }

    fn sub(&self, key: &str) -> String {
        if self.path.is_empty() || key.is_empty() || key.starts_with('[') {
            format!("{}{key}", self.path)
        } else {
            format!("{}.{key}", self.path)
        }
    }

    /// An error at `key` of this object: `FILE: PATH.KEY: message`.
    pub fn error(&self, key: &str, message: impl std::fmt::Display) -> ImportError {
        ImportError(format!("{}: {}: {message}", self.file, self.sub(key)))
    }

    /// A note on `key` (what was approximated), in the report's format.
    pub fn note(&self, key: &str, message: impl std::fmt::Display) -> String {
        format!("{}: {}: {message}", self.file, self.sub(key))
    }

    /// The value at `key`, marked as read.
    pub fn take(&self, key: &str) -> Option<&'a Value> {
        let v = self.map.get(key);
        if v.is_some() {
            self.used.borrow_mut().push(key.to_string());
        }
        v
    }

    /// The object `v` found at `rel` below this one (e.g. an array element `properties[0]`).
    pub fn child_at(&self, v: &'a Value, rel: &str) -> Result<Section<'a>, ImportError> {
        let map = v.as_object().ok_or_else(|| self.error(rel, "must be a JSON object"))?;
        Ok(Section { map, path: self.sub(rel), file: self.file, used: RefCell::new(Vec::new()) })
    }

    /// The required object at `key`.
    pub fn object(&self, key: &str) -> Result<Section<'a>, ImportError> {
        let v = self.take(key).ok_or_else(|| self.error(key, "missing"))?;
        self.child_at(v, key)
    }

    /// The object at `key`, if present.
    pub fn optional_object(&self, key: &str) -> Result<Option<Section<'a>>, ImportError> {
        self.take(key).map(|v| self.child_at(v, key)).transpose()
    }

    /// The required array at `key`.
    pub fn array(&self, key: &str) -> Result<&'a Vec<Value>, ImportError> {
        self.take(key)
            .ok_or_else(|| self.error(key, "missing"))?
            .as_array()
            .ok_or_else(|| self.error(key, "must be an array"))
    }

    /// The required string at `key`.
    pub fn string(&self, key: &str) -> Result<String, ImportError> {
        self.optional_string(key)?.ok_or_else(|| self.error(key, "missing"))
    }

    /// The string at `key`, if present.
    pub fn optional_string(&self, key: &str) -> Result<Option<String>, ImportError> {
        match self.take(key) {
            None => Ok(None),
            Some(Value::String(s)) => Ok(Some(s.clone())),
            Some(v) => Err(self.error(key, format!("must be a string, got {v}"))),
        }
    }

    /// The required finite number at `key`.
    pub fn number(&self, key: &str) -> Result<f64, ImportError> {
        self.optional_number(key)?.ok_or_else(|| self.error(key, "missing"))
    }

    /// The finite number at `key`, if present.
    pub fn optional_number(&self, key: &str) -> Result<Option<f64>, ImportError> {
        match self.take(key) {
            None => Ok(None),
            Some(v) => v
                .as_f64()
                .filter(|x| x.is_finite())
                .map(Some)
                .ok_or_else(|| self.error(key, format!("must be a number, got {v}"))),
        }
    }

    /// The boolean at `key`, if present.
    pub fn optional_bool(&self, key: &str) -> Result<Option<bool>, ImportError> {
        match self.take(key) {
            None => Ok(None),
            Some(Value::Bool(b)) => Ok(Some(*b)),
            Some(v) => Err(self.error(key, format!("must be true or false, got {v}"))),
        }
    }

    /// Marks `key` as read and reports it as ignored with `why` (if present).
    pub fn ignore(&self, key: &str, why: &str, notes: &mut Vec<String>) {
        if self.take(key).is_some() {
            notes.push(self.note(key, format!("ignored ({why})")));
        }
    }

    /// Reports every key not read as ignored.
    pub fn finish(&self, notes: &mut Vec<String>) {
        let used = self.used.borrow();
        for key in self.map.keys() {
            if !used.contains(key) {
                notes.push(self.note(key, "ignored (not understood by the importer)"));
            }
        }
    }
}
