//! Issue 28: the case-file documentation cannot drift from the parser. Every key that the
//! parser of a case file accepts, at every nesting level, is found from the code and looked
//! up in docs/cases.md.
//!
//! The keys come from serde itself, not from a hand list: a probe document with an
//! impossible key (`"\u{1}"`) placed at a JSON path makes the derived `Deserialize` of
//! [`Case`] answer what it expects there, in the words of `serde::de::Error`:
//!
//! - `unknown field `…`, expected one of `a`, `b`` — an object (every object refuses
//!   unknown keys): its keys, each explored in turn;
//! - `unknown variant `…`, expected one of …` — an externally tagged value
//!   (`{"rectangle": {...}}` or `"quad4"`): each variant explored as a key, a unit variant
//!   (`invalid type: map, expected unit`) being a value rather than a key;
//! - `missing field `law``, then `unknown variant` for `{"law": "\u{1}"}` — an internally
//!   tagged object: the tag, its values, and each variant's keys;
//! - `invalid type: map, expected a sequence` (or an array, a tuple) — an array: its
//!   entries explored;
//! - `invalid type: integer `0`` (the probe's value refused, its key accepted) — a map
//!   from names (`materials`, `regions`): its values explored;
//! - any other `invalid type: map` or an untagged enum (amplitudes) — a leaf.
//!
//! A message of any other form fails the test, so that a new kind of value is noticed.

use std::collections::BTreeSet;

use loam::case::Case;
use serde_json::{json, Map, Value};

/// The key no case may have: the probe.
const PROBE: &str = "\u{1}";

/// Deepest nesting explored (the deepest case key is at about 8).
const MAX_DEPTH: usize = 16;

/// One step from a value to a value inside it.
#[derive(Debug, Clone)]
enum Step {
    /// The value of a key.
    Key(String),
    /// An entry of an array.
    Entry,
    /// The value of a key of an internally tagged object `{tag: variant, key: ...}`.
    TaggedKey { tag: String, variant: String, key: String },
}

/// A key (or a value of an enumeration) the parser accepts, and where.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
struct Accepted {
    name: String,
    /// `true` for a key, `false` for a value (a unit variant: `"quad4"`, `"static"`).
    key: bool,
    /// JSON path of the object (or value) that accepts it, `[]` for any entry of an array and
    /// `*` for any name of a map.
    path: String,
}

struct Walker {
    found: BTreeSet<Accepted>,
    /// Messages of a form the walker does not know, with their paths.
    unknown: Vec<String>,
}

/// The document with `inner` at the end of `steps`.
fn wrap(steps: &[Step], inner: Value) -> Value {
    steps.iter().rev().fold(inner, |inner, step| match step {
        Step::Key(k) => json!({ k.as_str(): inner }),
        Step::Entry => json!([inner]),
        Step::TaggedKey { tag, variant, key } => {
            let mut m = Map::new();
            m.insert(tag.clone(), Value::String(variant.clone()));
            m.insert(key.clone(), inner);
            Value::Object(m)
        }
    })
}

/// What the case parser says about `document` (the empty string if it accepts it).
fn answer(document: Value) -> String {
    match serde_json::from_value::<Case>(document) {
        Ok(_) => String::new(),
        Err(e) => e.to_string(),
    }
}

/// The back-quoted names in `text` (serde's lists of expected fields and variants).
fn quoted(text: &str) -> Vec<String> {
    text.split('`').skip(1).step_by(2).map(str::to_string).collect()
}

/// The names serde lists after the probe in `unknown field `\u{1}`, expected ...`.
fn expected_after(message: &str, what: &str) -> Option<Vec<String>> {
    let head = format!("{what} `{PROBE}`");
    let i = message.find(&head)?;
    Some(quoted(&message[i + head.len()..]))
}

fn path_string(steps: &[Step]) -> String {
    let mut s = String::new();
    for step in steps {
        match step {
            Step::Key(k) | Step::TaggedKey { key: k, .. } => {
                if !s.is_empty() {
                    s.push('.');
                }
                s.push_str(if k == PROBE { "*" } else { k });
            }
            Step::Entry => s.push_str("[]"),
        }
    }
    s
}

impl Walker {
    fn record(&mut self, name: &str, key: bool, steps: &[Step]) {
        self.found.insert(Accepted { name: name.to_string(), key, path: path_string(steps) });
    }

    /// Explores the value at `steps`.
    fn explore(&mut self, steps: &[Step]) {
        if steps.len() > MAX_DEPTH {
            self.unknown.push(format!("{}: nested deeper than {MAX_DEPTH}", path_string(steps)));
            return;
        }
        let message = answer(wrap(steps, json!({ PROBE: 0 })));
        let child = |step: Step| {
            let mut s = steps.to_vec();
            s.push(step);
            s
        };
        if let Some(fields) = expected_after(&message, "unknown field") {
            for f in fields {
                self.record(&f, true, steps);
                self.explore(&child(Step::Key(f)));
            }
        } else if let Some(variants) = expected_after(&message, "unknown variant") {
            for v in variants {
                let inner = answer(wrap(&child(Step::Key(v.clone())), json!({ PROBE: 0 })));
                if inner.starts_with("invalid type: map, expected unit") {
                    self.record(&v, false, steps);
                } else {
                    self.record(&v, true, steps);
                    self.explore(&child(Step::Key(v)));
                }
            }
        } else if let Some(tag) = message.strip_prefix("missing field `").and_then(|m| m.split('`').next()) {
            self.explore_tagged(steps, tag.to_string(), &message);
        } else if message.starts_with("invalid type: map, expected a sequence")
            || message.starts_with("invalid type: map, expected an array")
            || message.starts_with("invalid type: map, expected a tuple")
        {
            self.explore(&child(Step::Entry));
        } else if message.starts_with("invalid type: integer `0`") {
            self.explore(&child(Step::Key(PROBE.to_string())));
        } else if message.starts_with("invalid type: map, expected")
            || message.starts_with("data did not match any variant of untagged enum")
        {
            // a leaf: a number, a string, a boolean, an amplitude
        } else {
            self.unknown.push(format!("{}: {message}", path_string(steps)));
        }
    }

    /// Explores the internally tagged object at `steps` whose tag is `tag`.
    fn explore_tagged(&mut self, steps: &[Step], tag: String, first: &str) {
        let message = answer(wrap(steps, json!({ tag.as_str(): PROBE })));
        let Some(variants) = expected_after(&message, "unknown variant") else {
            self.unknown.push(format!("{}: {first}; with `{tag}`: {message}", path_string(steps)));
            return;
        };
        self.record(&tag, true, steps);
        for v in variants {
            self.record(&v, false, steps);
            let mut object = Map::new();
            object.insert(tag.clone(), Value::String(v.clone()));
            object.insert(PROBE.to_string(), json!(0));
            let message = answer(wrap(steps, Value::Object(object)));
            let Some(fields) = expected_after(&message, "unknown field") else {
                self.unknown.push(format!("{} ({tag} {v}): {message}", path_string(steps)));
                continue;
            };
            for f in fields {
                self.record(&f, true, steps);
                let mut s = steps.to_vec();
                s.push(Step::TaggedKey { tag: tag.clone(), variant: v.clone(), key: f });
                self.explore(&s);
            }
        }
    }
}

/// Every key and enumerated value of a case file, from the parser.
fn accepted() -> BTreeSet<Accepted> {
    let mut walker = Walker { found: BTreeSet::new(), unknown: Vec::new() };
    walker.explore(&[]);
    assert!(walker.unknown.is_empty(), "answers the walker does not understand:\n{}", walker.unknown.join("\n"));
    walker.found
}

/// Whether docs/cases.md names `name` as `"name"` or `` `name` ``.
fn documented(docs: &str, name: &str) -> bool {
    docs.contains(&format!("\"{name}\"")) || docs.contains(&format!("`{name}`"))
}

/// The walker finds the keys it must: a sample at every kind of nesting.
#[test]
fn the_walker_finds_keys_at_every_level() {
    let found = accepted();
    let has =
        |name: &str, key: bool, path: &str| found.contains(&Accepted { name: name.into(), key, path: path.into() });
    assert!(has("description", true, ""));
    assert!(has("cells", true, "domains[].grid"));
    assert!(has("rectangle", true, "domains[].mesh"));
    assert!(has("origin", true, "domains[].mesh.rectangle"));
    assert!(has("quad4", false, "domains[].grid.element"));
    assert!(has("law", true, "materials.*"));
    assert!(has("preconsolidation_pressure", true, "materials.*"));
    assert!(has("type", true, "monitors[]"));
    assert!(has("runout", false, "monitors[]"));
    assert!(has("min", true, "monitors[].box"));
    assert!(has("newmark", true, "analysis.scheme"));
    assert!(has("beta", true, "analysis.scheme.newmark"));
    assert!(has("geostatic", true, "domains[].initial_stress"));
    assert!(has("all", true, "regions.*"));
    assert!(has("mpm_pattern_rings", true, "solver"));
    assert!(found.len() > 200, "only {} keys and values found", found.len());
}

/// Every key the case parser accepts, and every value of an enumeration, is in docs/cases.md.
#[test]
fn every_case_key_is_documented() {
    let docs = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/cases.md")).unwrap();
    let missing: Vec<String> = accepted()
        .into_iter()
        .filter(|a| !documented(&docs, &a.name))
        .map(|a| format!("{} `{}` at {}", if a.key { "key" } else { "value" }, a.name, a.path))
        .collect();
    assert!(missing.is_empty(), "docs/cases.md does not document:\n{}", missing.join("\n"));
}
