//! Shape checks of hand-written JSON objects (transfer functions, cameras), so that a wrong
//! shape is reported with the field's name and the expected shape rather than serde's
//! position-only message. JSON syntax errors keep serde's message with line and column.
use serde_json::{Map, Value};

use crate::error::{Error, Result};

/// A parsed JSON object.
pub(crate) type Object = Map<String, Value>;

/// What a number field accepts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum NumberKind {
    /// Any finite number.
    Any,
    /// A number > 0.
    Positive,
    /// A number >= 0.
    NonNegative,
}

/// Parses `text` as a JSON object; `wrap` turns a shape message into the caller's error.
/// Syntax errors are [`Error::Json`] (serde's message with line and column).
pub(crate) fn parse_object(
    text: &str,
    fields: &[&str],
    wrap: fn(String) -> Error,
) -> Result<Object> {
    match serde_json::from_str::<Value>(text)? {
        Value::Object(obj) => Ok(obj),
        other => Err(wrap(format!(
            "expected a JSON object with fields {}, got {}",
            fields.join(", "),
            describe(&other)
        ))),
    }
}

/// A short description of a JSON value for messages: `5 numbers`, `"abc"`, `an object`.
pub(crate) fn describe(v: &Value) -> String {
    match v {
        Value::Null => "null".into(),
        Value::Bool(b) => b.to_string(),
        Value::Number(n) => n.to_string(),
        Value::String(s) => format!("{s:?}"),
        Value::Object(_) => "an object".into(),
        Value::Array(a) if a.iter().all(Value::is_number) => match a.len() {
            1 => "1 number".into(),
            n => format!("{n} numbers"),
        },
        Value::Array(_) => {
            let text = v.to_string();
            if text.chars().count() > 40 {
                format!("{}...", text.chars().take(37).collect::<String>())
            } else {
                text
            }
        }
    }
}

/// Rejects fields not in `known`.
pub(crate) fn check_known(obj: &Object, known: &[&str]) -> Result<(), String> {
    match obj.keys().find(|k| !known.contains(&k.as_str())) {
        Some(k) => Err(format!(
            "unknown field {k:?} (expected one of {})",
            known.join(", ")
        )),
        None => Ok(()),
    }
}

/// Checks that `v` is an array of exactly `n` numbers; `label` names it, `shape` shows it
/// (e.g. `[value, tau]`).
pub(crate) fn check_tuple(label: &str, v: &Value, n: usize, shape: &str) -> Result<(), String> {
    match v {
        Value::Array(a) if a.len() == n && a.iter().all(Value::is_number) => Ok(()),
        _ => Err(format!(
            "{label}: expected {shape} ({n} numbers), got {}",
            describe(v)
        )),
    }
}

/// Checks the optional field `field` is a list of `[n numbers]` points.
pub(crate) fn check_points(obj: &Object, field: &str, n: usize, shape: &str) -> Result<(), String> {
    match obj.get(field) {
        None => Ok(()),
        Some(Value::Array(points)) => points
            .iter()
            .enumerate()
            .try_for_each(|(i, p)| check_tuple(&format!("{field}[{i}]"), p, n, shape)),
        Some(other) => Err(format!(
            "{field}: expected a list of {shape} points, got {}",
            describe(other)
        )),
    }
}

/// Checks the optional field `field` is a number of the given kind.
pub(crate) fn check_number(obj: &Object, field: &str, kind: NumberKind) -> Result<(), String> {
    let Some(v) = obj.get(field) else {
        return Ok(());
    };
    let ok = v.as_f64().is_some_and(|x| match kind {
        NumberKind::Any => x.is_finite(),
        NumberKind::Positive => x.is_finite() && x > 0.0,
        NumberKind::NonNegative => x.is_finite() && x >= 0.0,
    });
    if ok {
        return Ok(());
    }
    let what = match kind {
        NumberKind::Any => "a number",
        NumberKind::Positive => "a positive number",
        NumberKind::NonNegative => "a number >= 0",
    };
    Err(format!("{field}: expected {what}, got {}", describe(v)))
}

/// Checks the optional field `field` is one of the strings `choices`.
pub(crate) fn check_choice(obj: &Object, field: &str, choices: &[&str]) -> Result<(), String> {
    let Some(v) = obj.get(field) else {
        return Ok(());
    };
    if v.as_str().is_some_and(|s| choices.contains(&s)) {
        return Ok(());
    }
    let quoted: Vec<String> = choices.iter().map(|c| format!("{c:?}")).collect();
    let expected = match quoted.split_last() {
        Some((last, rest)) if !rest.is_empty() => format!("{} or {last}", rest.join(", ")),
        _ => quoted.join(""),
    };
    Err(format!("{field}: expected {expected}, got {}", describe(v)))
}

/// Checks that the required field `field` is present; `shape` describes what it holds.
pub(crate) fn check_required(obj: &Object, field: &str, shape: &str) -> Result<(), String> {
    if obj.contains_key(field) {
        Ok(())
    } else {
        Err(format!("missing field {field:?} ({shape})"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn obj(v: Value) -> Object {
        match v {
            Value::Object(o) => o,
            _ => unreachable!("test objects are objects"),
        }
    }

    #[test]
    fn describes_values_briefly() {
        assert_eq!(describe(&json!([1, 2, 3])), "3 numbers");
        assert_eq!(describe(&json!([1])), "1 number");
        assert_eq!(describe(&json!("abc")), "\"abc\"");
        assert_eq!(describe(&json!({"a": 1})), "an object");
        assert_eq!(describe(&json!(null)), "null");
        assert_eq!(describe(&json!([1, "a"])), "[1,\"a\"]");
        assert!(
            describe(&json!(["aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa"])).ends_with("...")
        );
    }

    #[test]
    fn object_parsing_keeps_syntax_positions() {
        let wrap = Error::InvalidCamera;
        assert!(parse_object(r#"{"a": 1}"#, &["a"], wrap).is_ok());
        let e = parse_object(r#"{"a": 1,, }"#, &["a"], wrap).unwrap_err();
        assert!(
            matches!(e, Error::Json(_)) && e.to_string().contains("line 1"),
            "{e}"
        );
        let e = parse_object("[1]", &["a", "b"], wrap)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("expected a JSON object with fields a, b, got 1 number"),
            "{e}"
        );
    }

    #[test]
    fn field_checks_name_the_field() {
        let o = obj(json!({"p": [[1, 2], [1, 2, 3]], "n": -1, "c": "x", "q": 5}));
        assert_eq!(
            check_points(&o, "p", 2, "[a, b]").unwrap_err(),
            "p[1]: expected [a, b] (2 numbers), got 3 numbers"
        );
        assert_eq!(
            check_points(&o, "q", 2, "[a, b]").unwrap_err(),
            "q: expected a list of [a, b] points, got 5"
        );
        assert!(check_points(&o, "absent", 2, "[a, b]").is_ok());
        assert!(check_number(&o, "n", NumberKind::Any).is_ok());
        assert_eq!(
            check_number(&o, "n", NumberKind::Positive).unwrap_err(),
            "n: expected a positive number, got -1"
        );
        assert!(check_number(&o, "c", NumberKind::NonNegative).is_err());
        assert_eq!(
            check_choice(&o, "c", &["a", "b", "d"]).unwrap_err(),
            "c: expected \"a\", \"b\" or \"d\", got \"x\""
        );
        assert!(check_choice(&o, "c", &["x"]).is_ok());
        assert_eq!(
            check_known(&o, &["p", "n"]).unwrap_err(),
            "unknown field \"c\" (expected one of p, n)"
        );
        assert!(check_required(&o, "p", "points").is_ok());
        assert_eq!(
            check_required(&o, "z", "points").unwrap_err(),
            "missing field \"z\" (points)"
        );
        assert!(check_tuple("t", &json!([1, 2, 3]), 3, "[x, y, z]").is_ok());
    }
}
