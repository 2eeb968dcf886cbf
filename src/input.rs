//! Reading JSON input files (case files, `loam law` path files) as a hostile or careless
//! user may write them (issue 16): a size limit before anything is read, strict JSON, and
//! errors that name the full JSON path.
//!
//! Two stages:
//!
//! 1. **Text → [`Value`]** by a strict visitor: a key given twice in one object is refused
//!    (serde_json keeps the last one silently: a second `"beam"` would hide the first), text
//!    after the top-level value is refused, nesting is bounded by serde_json's recursion
//!    limit (128). Syntax errors give the line and column and the JSON path reached.
//! 2. **[`Value`] → the typed file** through `serde_path_to_error`. Serde loses the path
//!    inside internally tagged enums (`{"type": "displacement", ...}`, `{"law": ...}`) and
//!    untagged ones (amplitudes), which it buffers before deciding the variant: an error
//!    there would name only the object (`materials.beam` for `"density": "1000"`). The
//!    error is then located inside that object from the [`Value`]: the one value serde
//!    names as unexpected (`string "1000"`), the one array of the length it names, the one
//!    key it calls unknown. Where more than one value fits, the object's path is kept: it
//!    is still right, only less precise.
//!
//! Messages are then made readable: an externally tagged value with several keys lists
//! them (`regions.clamp: takes exactly one key naming its kind, got 2: x, zz_typo`), and
//! numbers of more than 20 characters (Rust prints `1e300` with all its 301 digits) are
//! written in exponent form ([`compact_numbers`]).

use std::cell::RefCell;
use std::fmt;
use std::io::Read;
use std::path::Path;

use serde::de::{DeserializeOwned, DeserializeSeed, Error as _, MapAccess, SeqAccess, Unexpected, Visitor};
use serde_json::{Map, Value};

use crate::case::CaseError;

/// Largest JSON input file (case file, path file): 16 MiB. The bundled cases are a few
/// kB; a long amplitude table (an earthquake record of 100 000 samples) is about 3 MB.
pub const MAX_JSON_FILE_BYTES: u64 = 16 << 20;

/// Reads at most `limit` bytes of `path`, refusing larger files before reading them
/// (regular files) or once `limit` is passed (pipes, devices such as `/dev/zero`).
/// `what` names the file's role in messages (e.g. `case file`). The error is one line.
pub fn read_limited(path: &Path, limit: u64, what: &str) -> Result<Vec<u8>, String> {
    let file = std::fs::File::open(path).map_err(|e| format!("cannot read {what}: {e}"))?;
    let meta = file.metadata().map_err(|e| format!("cannot read {what}: {e}"))?;
    if meta.is_dir() {
        return Err(format!("cannot read {what}: is a directory"));
    }
    let too_large = |size: String| format!("{what} is {size} the limit of {}", bytes(limit));
    if meta.is_file() && meta.len() > limit {
        return Err(too_large(format!("{}, more than", bytes(meta.len()))));
    }
    let mut data = Vec::new();
    file.take(limit.saturating_add(1)).read_to_end(&mut data).map_err(|e| format!("cannot read {what}: {e}"))?;
    if data.len() as u64 > limit {
        return Err(too_large("larger than".into()));
    }
    Ok(data)
}

/// A byte count for messages: `16 MiB`, `2 GiB`, `1234 bytes`.
pub fn bytes(n: u64) -> String {
    const MIB: u64 = 1 << 20;
    if n >= 1 << 30 && n % (1 << 30) == 0 {
        format!("{} GiB", n >> 30)
    } else if n >= MIB && n % MIB == 0 {
        format!("{} MiB", n / MIB)
    } else if n >= 10 * MIB {
        format!("{:.1} MiB", n as f64 / MIB as f64)
    } else {
        format!("{n} bytes")
    }
}

/// Reads a JSON input file with [`read_limited`] ([`MAX_JSON_FILE_BYTES`]) as UTF-8 text.
pub fn read_json_text(path: &Path, what: &str) -> Result<String, CaseError> {
    let data =
        read_limited(path, MAX_JSON_FILE_BYTES, what).map_err(|m| CaseError::new(path.display().to_string(), m))?;
    String::from_utf8(data).map_err(|e| {
        CaseError::new(
            path.display().to_string(),
            format!("{what} is not UTF-8 text (invalid byte at offset {})", e.utf8_error().valid_up_to()),
        )
    })
}

/// Parses JSON `text` strictly into a [`Value`] (stage 1 of the module doc). Errors are
/// located at `line L column C` (with the JSON path reached, where there is one), or at the
/// path of a duplicate key.
pub fn parse_value(text: &str) -> Result<Value, CaseError> {
    let problem = RefCell::new(None);
    let mut de = serde_json::Deserializer::from_str(text);
    let seed = Strict { path: String::new(), problem: &problem };
    let result = seed.deserialize(&mut de).and_then(|v| de.end().map(|()| v));
    result.map_err(|e| {
        if let Some(p) = problem.borrow_mut().take() {
            if let Problem::Duplicate(error) = p {
                return error;
            }
            if let Problem::At(path) = p {
                return syntax_error(&e, &path);
            }
        }
        syntax_error(&e, "")
    })
}

fn syntax_error(e: &serde_json::Error, path: &str) -> CaseError {
    let message = compact_numbers(&strip_position(&e.to_string()));
    let message = match message.as_str() {
        "trailing characters" => "text after the end of the JSON object".to_string(),
        _ => message,
    };
    let location = format!("line {} column {}", e.line(), e.column());
    if path.is_empty() {
        CaseError::new(location, message)
    } else {
        CaseError::new(format!("{location} ({path})"), message)
    }
}

/// Reads the JSON file `path` (a `what`, e.g. "fit file") as strictly as a case file: the size
/// limit, duplicate keys, text after the object and unknown keys are errors located at
/// `FILE:line L column C`, at the full JSON path, or at the file.
pub fn read_strict<T: DeserializeOwned>(path: &Path, what: &str) -> Result<T, CaseError> {
    let text = read_json_text(path, what)?;
    parse(&text).map(|(file, _)| file).map_err(|mut e| {
        e.location = if e.location.is_empty() {
            path.display().to_string()
        } else if e.location.starts_with("line") {
            format!("{}:{}", path.display(), e.location)
        } else {
            e.location
        };
        e
    })
}

/// Parses `text` strictly and deserializes a `T` from it, with every error naming its JSON
/// path (module doc). A missing key at the top level has the location `""`.
pub fn parse<T: DeserializeOwned>(text: &str) -> Result<(T, Value), CaseError> {
    let value = parse_value(text)?;
    check_object(&value)?;
    let typed = from_value(&value)?;
    Ok((typed, value))
}

/// The error of a file whose top level is not one JSON object.
pub fn check_object(value: &Value) -> Result<(), CaseError> {
    if !value.is_object() {
        let got = describe(value).unwrap_or_default().replace("unit value", "null").replace("sequence", "an array");
        return Err(CaseError::new("", format!("must be one JSON object {{ ... }}, got {got}")));
    }
    Ok(())
}

/// Deserializes a `T` from `value` (stage 2 of the module doc).
pub fn from_value<T: DeserializeOwned>(value: &Value) -> Result<T, CaseError> {
    serde_path_to_error::deserialize(value.clone()).map_err(|e| {
        let segments: Vec<Segment> = e
            .path()
            .iter()
            .filter_map(|s| match s {
                serde_path_to_error::Segment::Seq { index } => Some(Segment::Index(*index)),
                serde_path_to_error::Segment::Map { key } | serde_path_to_error::Segment::Enum { variant: key } => {
                    Some(Segment::Key(key.clone()))
                }
                serde_path_to_error::Segment::Unknown => None,
            })
            .collect();
        let message = strip_position(&e.into_inner().to_string());
        locate(value, &segments, &message, &|at| names_at::<T>(value, at))
    })
}

/// The names (enumerated values, kinds) that `T` accepts at `at` inside `value`, asked of
/// serde itself: the value there replaced by an impossible name makes the derived
/// `Deserialize` list them (`unknown variant ..., expected one of ...`); and whether the
/// first one is a value of its own (`"static"`) rather than the key of an object
/// (`{"rectangle": ...}`). `None` where any string is accepted.
fn names_at<T: DeserializeOwned>(value: &Value, at: &[Segment]) -> Option<Names> {
    const PROBE: &str = "\u{1}";
    let answer_with = |name: &str| {
        let mut probe = value.clone();
        let node = at.iter().try_fold(&mut probe, |v, s| match (s, v) {
            (Segment::Key(k), Value::Object(m)) => m.get_mut(k),
            (Segment::Index(i), Value::Array(a)) => a.get_mut(*i),
            _ => None,
        })?;
        *node = Value::String(name.to_string());
        Some(serde_json::from_value::<T>(probe).err().map(|e| e.to_string()).unwrap_or_default())
    };
    let answer = answer_with(PROBE)?;
    let (_, list) = answer.split_once(&format!("unknown variant `{PROBE}`"))?;
    let names: Vec<String> = list.split('`').skip(1).step_by(2).map(str::to_string).collect();
    let first = answer_with(names.first()?)?;
    let alone = !(first.contains("unit value") || first.contains("unit variant"));
    Some(Names { names, alone })
}

/// The names a value may take ([`names_at`]).
struct Names {
    names: Vec<String>,
    /// Whether the first name is a value of its own (`"static"`), else the key of an object
    /// (`{"rectangle": ...}`).
    alone: bool,
}

/// One step of a JSON path.
#[derive(Debug, Clone, PartialEq)]
enum Segment {
    Key(String),
    Index(usize),
}

/// `a.b[0].c` as serde_path_to_error writes it.
fn path_string(segments: &[Segment]) -> String {
    let mut s = String::new();
    for seg in segments {
        match seg {
            Segment::Key(k) => {
                if !s.is_empty() {
                    s.push('.');
                }
                s.push_str(k);
            }
            Segment::Index(i) => s.push_str(&format!("[{i}]")),
        }
    }
    s
}

/// The error `message` that serde gave at `segments`, located as precisely as `value`
/// allows and reworded where serde's words mislead.
fn locate(
    value: &Value,
    segments: &[Segment],
    message: &str,
    names_at: &dyn Fn(&[Segment]) -> Option<Names>,
) -> CaseError {
    // descend as far as the value follows the path
    let mut node = value;
    let mut path: Vec<Segment> = Vec::new();
    for seg in segments {
        let next = match (seg, node) {
            (Segment::Key(k), Value::Object(m)) => m.get(k),
            (Segment::Index(i), Value::Array(a)) => a.get(*i),
            _ => None,
        };
        match next {
            Some(n) => {
                node = n;
                path.push(seg.clone());
            }
            None => break,
        }
    }
    let mut message = message.to_string();
    if let Some(found) = culprit(node, &message) {
        path.extend(found);
    }
    let here = path.iter().try_fold(value, |v, s| match (s, v) {
        (Segment::Key(k), Value::Object(m)) => m.get(k),
        (Segment::Index(i), Value::Array(a)) => a.get(*i),
        _ => None,
    });
    if message.ends_with("expected map with a single key") {
        if let Some(Value::Object(m)) = here {
            let keys: Vec<&str> = m.keys().map(String::as_str).collect();
            message = match keys.len() {
                0 => "takes exactly one key naming its kind, got none".to_string(),
                n => format!("takes exactly one key naming its kind, got {n}: {}", keys.join(", ")),
            };
        }
    }
    message = message
        .replace("expected string or map", "expected a name in quotes or an object with one key")
        .replace("expected fewer elements in array", "expected fewer entries")
        .replace("expected variant identifier", "expected the name of a kind in quotes");
    if let Some(i) = message.find("expected internally tagged enum ") {
        message = format!("{}expected an object naming its kind (\"type\" or \"law\")", &message[..i]);
    }
    if let Some(rest) = message.strip_prefix("data did not match any variant of untagged enum Amplitude") {
        message = format!("expected a number or a table [[t, f], ...] of increasing times{rest}");
    }
    let key = path.iter().rev().find_map(|s| match s {
        Segment::Key(k) => Some(k.as_str()),
        Segment::Index(_) => None,
    });
    let names = if message.contains(", expected a name in quotes") || message.contains(", expected the name of a kind")
    {
        names_at(&path)
    } else {
        None
    };
    let message = teach(&message, here, key.unwrap_or(""), names);
    CaseError::new(path_string(&path), compact_numbers(&message))
}

/// Serde's `message` about the value `here` at `key` made to teach (issue 28): the valid
/// name nearest to an unknown one (`did you mean "young_modulus"?`), plain words for types
/// (`a number`, not `f64`), and an example of what is expected; `names` are the names the
/// value may take, where it is one of a list.
fn teach(message: &str, here: Option<&Value>, key: &str, names: Option<Names>) -> String {
    use crate::hints::{did_you_mean, example_value, example_vector};
    for (head, noun) in [("unknown field `", "unknown field `"), ("unknown variant `", "unknown value `")] {
        if let Some((name, tail)) = message.strip_prefix(head).and_then(|rest| rest.split_once('`')) {
            let names: Vec<&str> = tail.split('`').skip(1).step_by(2).collect();
            let hint = did_you_mean(name, names);
            return format!("{noun}{name}`, {hint}{}", tail.trim_start_matches(", "));
        }
    }
    if let Some(name) = message.strip_prefix("missing field `").and_then(|rest| rest.strip_suffix('`')) {
        let example = match (name, key) {
            ("type", "analysis") => Some("\"static\""),
            ("type", "monitors") => Some("\"displacement\""),
            ("type", "loads") => Some("\"nodal_force\""),
            ("origin" | "size" | "cells" | "point" | "acceleration" | "from" | "to" | "min" | "max", _) => {
                Some(example_vector(name, 2).1)
            }
            _ => example_value(name),
        };
        return match example {
            Some(example) => format!("{message}, e.g. \"{name}\": {example}"),
            None => message.to_string(),
        };
    }
    if let Some((_, n)) =
        message.strip_prefix("invalid length ").and_then(|r| r.split_once(", expected an array of length "))
    {
        if let Ok(n) = n.parse::<usize>() {
            let (what, example) = example_vector(key, n);
            let got = here.map(|v| format!(", got {}", v.to_string().replace(',', ", "))).unwrap_or_default();
            return format!("{message} ({what}), e.g. {example}{got}");
        }
    }
    let Some((head, expected)) = message.split_once(", expected ") else { return message.to_string() };
    if let Some(Names { names, alone }) = names {
        let listed: Vec<String> = names.iter().map(|n| format!("`{n}`")).collect();
        let (words, example) = if alone {
            ("the name of a kind in quotes", format!("\"{}\"", names[0]))
        } else {
            ("an object with one key naming its kind", format!("{{\"{}\": ...}}", names[0]))
        };
        return format!("{head}, expected {words}, one of {}, e.g. {example}", listed.join(", "));
    }
    if !(head.starts_with("invalid type: ") || head.starts_with("invalid value: ")) {
        return message.to_string();
    }
    let (words, fallback) = match expected {
        "f64" | "f32" => ("a number", "1.0"),
        "usize" | "u64" | "u32" | "u16" | "u8" => ("a whole number ≥ 0", "4"),
        "a boolean" => ("true or false", "true"),
        "a string" | "path string" => ("a name in quotes", "\"beam\""),
        _ => return message.to_string(),
    };
    let unquoted = match here {
        Some(Value::String(s)) if words != "a name in quotes" && s.trim().parse::<f64>().is_ok() => Some(s.trim()),
        _ => None,
    };
    match unquoted {
        Some(number) => format!("{head}, expected {words}, e.g. {number} (without the quotes)"),
        None => format!("{head}, expected {words}, e.g. {}", example_value(key).unwrap_or(fallback)),
    }
}

/// Where inside `node` the value that `message` complains about lies: the first (in the
/// order serde visits) of the values it could be, if it is the only one; `None` if the
/// message names nothing to search for, or several values fit.
fn culprit(node: &Value, message: &str) -> Option<Vec<Segment>> {
    let quoted = |after: &str| -> Option<String> {
        let rest = message.strip_prefix(after)?;
        let rest = rest.strip_prefix('`')?;
        Some(rest[..rest.find('`')?].to_string())
    };
    let mut found = Vec::new();
    let mut path = Vec::new();
    if let Some(rest) = message.strip_prefix("invalid type: ") {
        let unexpected = rest.rsplit_once(", expected ").map_or(rest, |(u, _)| u);
        search(node, &mut path, &mut found, &|v, _| describe(v).as_deref() == Some(unexpected));
    } else if let Some(rest) = message.strip_prefix("invalid length ") {
        let n: usize = rest.split(|c: char| !c.is_ascii_digit()).next()?.parse().ok()?;
        search(node, &mut path, &mut found, &|v, _| matches!(v, Value::Array(a) if a.len() == n));
    } else if let Some(key) = quoted("unknown field ") {
        search(node, &mut path, &mut found, &|_, k| k == Some(key.as_str()));
    } else if let Some(name) = quoted("unknown variant ") {
        search(node, &mut path, &mut found, &|v, k| {
            matches!(v, Value::String(s) if *s == name) || (k == Some(name.as_str()))
        });
    } else if message.starts_with("data did not match any variant of untagged enum Amplitude") {
        search(node, &mut path, &mut found, &|_, k| k == Some("amplitude"));
    } else {
        return None;
    }
    match found.len() {
        1 => found.pop(),
        _ => None,
    }
}

/// Depth-first search of `node` (itself included) for values `hit(value, key)` accepts.
fn search(
    node: &Value,
    path: &mut Vec<Segment>,
    found: &mut Vec<Vec<Segment>>,
    hit: &dyn Fn(&Value, Option<&str>) -> bool,
) {
    let key = match path.last() {
        Some(Segment::Key(k)) => Some(k.as_str()),
        _ => None,
    };
    if hit(node, key) {
        found.push(path.clone());
    }
    match node {
        Value::Object(m) => {
            for (k, v) in m {
                path.push(Segment::Key(k.clone()));
                search(v, path, found, hit);
                path.pop();
            }
        }
        Value::Array(a) => {
            for (i, v) in a.iter().enumerate() {
                path.push(Segment::Index(i));
                search(v, path, found, hit);
                path.pop();
            }
        }
        _ => {}
    }
}

/// How serde describes `v` as an unexpected value (`string "1000"`, `integer `1``, ...).
fn describe(v: &Value) -> Option<String> {
    let u = match v {
        Value::Null => Unexpected::Unit,
        Value::Bool(b) => Unexpected::Bool(*b),
        Value::Number(n) => match (n.as_u64(), n.as_i64(), n.as_f64()) {
            (Some(u), _, _) => Unexpected::Unsigned(u),
            (None, Some(i), _) => Unexpected::Signed(i),
            (None, None, Some(f)) => Unexpected::Float(f),
            _ => return None,
        },
        Value::String(s) => Unexpected::Str(s),
        Value::Array(_) => Unexpected::Seq,
        Value::Object(_) => Unexpected::Map,
    };
    Some(u.to_string())
}

/// serde_json appends " at line L column C"; the path already says where.
pub fn strip_position(message: &str) -> String {
    match message.rfind(" at line ") {
        Some(i) => message[..i].to_string(),
        None => message.to_string(),
    }
}

/// Writes every number of more than 20 characters in `text` in exponent form: Rust prints
/// `1e300` as a 1 and 300 zeros, and `1e-300` as 300 zeros and a 1.
pub fn compact_numbers(text: &str) -> String {
    let chars: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    while i < chars.len() {
        let starts_number = chars[i].is_ascii_digit() && (i == 0 || !is_word(chars[i - 1]));
        if !starts_number {
            out.push(chars[i]);
            i += 1;
            continue;
        }
        let start = i;
        while i < chars.len() && (chars[i].is_ascii_digit() || chars[i] == '.') {
            i += 1;
        }
        let token: String = chars[start..i].iter().collect();
        match token.trim_end_matches('.').parse::<f64>() {
            Ok(v) if token.len() > 20 => {
                out.push_str(&format!("{v:e}"));
                if token.ends_with('.') {
                    out.push('.');
                }
            }
            _ => out.push_str(&token),
        }
    }
    out
}

fn is_word(c: char) -> bool {
    c.is_alphanumeric() || c == '_' || c == '.'
}

/// What went wrong in stage 1, beyond serde_json's own error.
enum Problem {
    /// The innermost JSON path reached when an error occurred.
    At(String),
    /// A key given twice.
    Duplicate(CaseError),
}

/// Stage 1's visitor: builds a [`Value`], refusing duplicate keys; `path` is where it is.
struct Strict<'a> {
    path: String,
    problem: &'a RefCell<Option<Problem>>,
}

impl Strict<'_> {
    fn child(&self, segment: &str) -> Self {
        Strict { path: format!("{}{segment}", self.path), problem: self.problem }
    }

    /// Records the innermost path at which an error passed (the first to record wins).
    fn note<E>(&self, e: E) -> E {
        note_at(self.problem, &self.path);
        e
    }
}

/// Records `path` as where an error occurred unless an inner one was recorded.
fn note_at(problem: &RefCell<Option<Problem>>, path: &str) {
    let mut p = problem.borrow_mut();
    if p.is_none() && !path.is_empty() {
        *p = Some(Problem::At(path.to_string()));
    }
}

impl<'de> DeserializeSeed<'de> for Strict<'_> {
    type Value = Value;

    fn deserialize<D: serde::Deserializer<'de>>(self, d: D) -> Result<Value, D::Error> {
        d.deserialize_any(self)
    }
}

impl<'de> Visitor<'de> for Strict<'_> {
    type Value = Value;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a JSON value")
    }

    fn visit_bool<E>(self, v: bool) -> Result<Value, E> {
        Ok(Value::Bool(v))
    }

    fn visit_i64<E>(self, v: i64) -> Result<Value, E> {
        Ok(Value::from(v))
    }

    fn visit_u64<E>(self, v: u64) -> Result<Value, E> {
        Ok(Value::from(v))
    }

    fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<Value, E> {
        serde_json::Number::from_f64(v).map(Value::Number).ok_or_else(|| E::custom("number out of range"))
    }

    fn visit_str<E>(self, v: &str) -> Result<Value, E> {
        Ok(Value::String(v.to_string()))
    }

    fn visit_string<E>(self, v: String) -> Result<Value, E> {
        Ok(Value::String(v))
    }

    fn visit_unit<E>(self) -> Result<Value, E> {
        Ok(Value::Null)
    }

    fn visit_none<E>(self) -> Result<Value, E> {
        Ok(Value::Null)
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Value, A::Error> {
        let mut items = Vec::new();
        loop {
            let child = self.child(&format!("[{}]", items.len()));
            let child_path = child.path.clone();
            match seq.next_element_seed(child) {
                Ok(Some(v)) => items.push(v),
                Ok(None) => return Ok(Value::Array(items)),
                Err(e) => {
                    note_at(self.problem, &child_path);
                    return Err(e);
                }
            }
        }
    }

    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Value, A::Error> {
        let mut m = Map::new();
        loop {
            let key = match map.next_key::<String>() {
                Ok(Some(k)) => k,
                Ok(None) => return Ok(Value::Object(m)),
                Err(e) => return Err(self.note(e)),
            };
            let child = self.child(&if self.path.is_empty() { key.clone() } else { format!(".{key}") });
            if m.contains_key(&key) {
                let error = CaseError::new(
                    child.path.clone(),
                    "is given twice in the same object (the second would silently replace the first)",
                );
                *self.problem.borrow_mut() = Some(Problem::Duplicate(error));
                return Err(A::Error::custom("duplicate key"));
            }
            let child_path = child.path.clone();
            let value = map.next_value_seed(child).inspect_err(|_| note_at(self.problem, &child_path))?;
            m.insert(key, value);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, serde::Deserialize)]
    #[serde(deny_unknown_fields)]
    #[allow(dead_code)]
    struct Outer {
        items: Vec<Tagged>,
        #[serde(default)]
        size: Option<[f64; 2]>,
    }

    #[derive(Debug, serde::Deserialize)]
    #[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
    #[allow(dead_code)]
    enum Tagged {
        A { name: String, value: f64 },
        B { point: Vec<f64> },
    }

    fn err(text: &str) -> String {
        parse::<Outer>(text).unwrap_err().to_string()
    }

    /// Issue 16: errors inside internally tagged enums name the value, not the object.
    #[test]
    fn errors_inside_tagged_enums_name_the_value() {
        assert_eq!(
            err(r#"{"items": [{"type": "a", "name": "x", "value": "1000"}]}"#),
            "items[0].value: invalid type: string \"1000\", expected a number, e.g. 1000 (without the quotes)"
        );
        assert!(err(r#"{"items": [{"type": "b", "point": [1], "zz": 1}]}"#).starts_with("items[0].zz: unknown field"));
        assert!(err(r#"{"items": [{"type": "c"}]}"#).starts_with("items[0].type: unknown value `c`"));
        // a number where a name is expected: the names, asked of serde, with an example
        assert_eq!(
            err(r#"{"items": [{"type": 3}]}"#),
            "items[0].type: invalid type: integer `3`, expected the name of a kind in quotes, one of `a`, `b`, e.g. \"a\""
        );
        // two candidates: the object's path is kept
        assert!(err(r#"{"items": [{"type": "b", "point": ["1", "1"]}]}"#).starts_with("items[0]: invalid type"));
        assert_eq!(err(r#"{"items": [], "size": [1, 2, 3]}"#), "size: invalid length 3, expected fewer entries");
    }

    /// Issue 16: duplicate keys and text after the object are refused.
    #[test]
    fn duplicate_keys_and_trailing_text() {
        assert_eq!(
            err("{\"items\": [{\"type\": \"b\", \"point\": [], \"point\": [1]}]}"),
            "items[0].point: is given twice in the same object (the second would silently replace the first)"
        );
        assert_eq!(err("{\"items\": []} x"), "line 1 column 15: text after the end of the JSON object");
        assert_eq!(err("{\"items\": [{\"type\": }]}"), "line 1 column 21 (items[0].type): expected value");
    }

    #[test]
    fn long_numbers_in_exponent_form() {
        let big = format!("{}", 1e300);
        assert_eq!(compact_numbers(&format!("must be > 0, got -{big}")), "must be > 0, got -1e300");
        assert_eq!(compact_numbers(&format!("got {}.", 1e-300)), "got 1e-300.");
        assert_eq!(
            compact_numbers("cell 12 at (1.5, 2) line 3 column 5 and x1234567890123456789012"),
            "cell 12 at (1.5, 2) line 3 column 5 and x1234567890123456789012"
        );
    }

    #[test]
    fn file_size_limits() {
        let err = read_limited(Path::new("/dev/zero"), 1 << 20, "case file").unwrap_err();
        assert_eq!(err, "case file is larger than the limit of 1 MiB");
        assert!(read_limited(Path::new("/"), 10, "case file").unwrap_err().contains("is a directory"));
    }
}
