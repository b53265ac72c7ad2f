//! `pge.params`: declared parameters, with overrides from `--set`, the preview's sliders or
//! `pge.load(path, {...})`.

use std::fmt;

use mlua::{Lua, Table, Value};

use super::errors::{caller_location, script_error};
use crate::Location;

/// The value of a parameter.
#[derive(Clone, Debug, PartialEq)]
pub enum ParamValue {
    /// An integer (a default written without a decimal point).
    Integer(i64),
    /// A number.
    Number(f64),
    /// A boolean.
    Bool(bool),
    /// A string.
    Text(String),
}

impl ParamValue {
    /// The value as a number, if it is one.
    #[must_use]
    pub fn as_f64(&self) -> Option<f64> {
        match self {
            ParamValue::Integer(i) => Some(*i as f64),
            ParamValue::Number(n) => Some(*n),
            _ => None,
        }
    }

    fn kind(&self) -> &'static str {
        match self {
            ParamValue::Integer(_) => "an integer",
            ParamValue::Number(_) => "a number",
            ParamValue::Bool(_) => "a boolean",
            ParamValue::Text(_) => "a string",
        }
    }

    /// Reads `text` as a value of the same kind as `self` (how `--set` values are typed).
    pub fn parse_like(&self, text: &str) -> Result<ParamValue, OverrideError> {
        let t = text.trim();
        let not_a_number = || OverrideError::NotANumber(text.to_string());
        match self {
            ParamValue::Integer(_) => match t.parse::<i64>() {
                Ok(i) => Ok(ParamValue::Integer(i)),
                Err(_) => match t.parse::<f64>() {
                    Ok(n) if n.is_finite() => Ok(ParamValue::Number(n)),
                    _ => Err(not_a_number()),
                },
            },
            ParamValue::Number(_) => match t.parse::<f64>() {
                Ok(n) if n.is_finite() => Ok(ParamValue::Number(n)),
                _ => Err(not_a_number()),
            },
            ParamValue::Bool(_) => match t {
                "true" | "1" | "yes" | "on" => Ok(ParamValue::Bool(true)),
                "false" | "0" | "no" | "off" => Ok(ParamValue::Bool(false)),
                _ => Err(OverrideError::NotABoolean(text.to_string())),
            },
            ParamValue::Text(_) => Ok(ParamValue::Text(text.to_string())),
        }
    }

    fn from_lua(v: &Value) -> Option<ParamValue> {
        match v {
            Value::Integer(i) => Some(ParamValue::Integer(*i)),
            Value::Number(n) => Some(ParamValue::Number(*n)),
            Value::Boolean(b) => Some(ParamValue::Bool(*b)),
            Value::String(s) => Some(ParamValue::Text(s.to_string_lossy())),
            _ => None,
        }
    }

    fn into_lua(self, lua: &Lua) -> mlua::Result<Value> {
        Ok(match self {
            ParamValue::Integer(i) => Value::Integer(i),
            ParamValue::Number(n) => Value::Number(n),
            ParamValue::Bool(b) => Value::Boolean(b),
            ParamValue::Text(s) => Value::String(lua.create_string(s)?),
        })
    }

    /// The value as JSON (for the glTF extras).
    #[must_use]
    pub fn to_json(&self) -> serde_json::Value {
        match self {
            ParamValue::Integer(i) => (*i).into(),
            ParamValue::Number(n) => {
                serde_json::Number::from_f64(*n).map_or(serde_json::Value::Null, Into::into)
            }
            ParamValue::Bool(b) => (*b).into(),
            ParamValue::Text(s) => s.clone().into(),
        }
    }
}

impl fmt::Display for ParamValue {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ParamValue::Integer(i) => write!(f, "{i}"),
            ParamValue::Number(n) => write!(f, "{n}"),
            ParamValue::Bool(b) => write!(f, "{b}"),
            ParamValue::Text(s) => write!(f, "{s}"),
        }
    }
}

/// A declared parameter and the value the script received.
#[derive(Clone, Debug, PartialEq)]
pub struct ParamInfo {
    /// Its name.
    pub name: String,
    /// The declared default.
    pub default: ParamValue,
    /// The value in force (default or override).
    pub value: ParamValue,
    /// Lower bound for numbers.
    pub min: Option<f64>,
    /// Upper bound for numbers.
    pub max: Option<f64>,
    /// What it means.
    pub doc: Option<String>,
}

/// An override not yet typed (from `--set`) or already a value (from `pge.load`).
#[derive(Clone, Debug)]
enum Override {
    Text(String),
    Value(ParamValue),
}

/// The parameters of one script run (the main script, or one `pge.load`).
#[derive(Debug)]
struct Scope {
    script: String,
    overrides: Vec<(String, Override)>,
    declared: Vec<ParamInfo>,
    first_call: Option<Location>,
}

/// The stack of parameter scopes; the bottom one is the main script's.
#[derive(Debug, Default)]
pub(crate) struct ParamState {
    scopes: Vec<Scope>,
    /// The main script's declarations, kept after it ran.
    pub main: Vec<ParamInfo>,
}

/// Sets the `--set` overrides for the main script.
pub(crate) fn begin_main(lua: &Lua, script: &str, overrides: &[(String, String)]) {
    let scope = Scope {
        script: script.to_string(),
        overrides: overrides
            .iter()
            .map(|(k, v)| (k.clone(), Override::Text(v.clone())))
            .collect(),
        declared: Vec::new(),
        first_call: None,
    };
    lua.set_app_data(ParamState {
        scopes: vec![scope],
        main: Vec::new(),
    });
}

/// Ends the main script: keeps its declarations; an override nobody declared is an error.
pub(crate) fn end_main(lua: &Lua) -> Result<(), (Location, String)> {
    let Some(mut st) = lua.app_data_mut::<ParamState>() else {
        return Ok(());
    };
    let Some(scope) = st.scopes.pop() else {
        return Ok(());
    };
    st.main = scope.declared.clone();
    unused_overrides(&scope, "--set").map_err(|m| {
        let loc = scope.first_call.clone().unwrap_or(Location {
            file: scope.script.clone(),
            line: None,
        });
        (loc, m.to_string())
    })
}

pub(crate) fn push_scope(lua: &Lua, script: &str, overrides: Option<Table>) -> mlua::Result<()> {
    let mut list = Vec::new();
    if let Some(t) = overrides {
        for (k, v) in super::sorted_pairs(&t)? {
            let k = <String as mlua::FromLua>::from_lua(k, lua)?;
            let value = ParamValue::from_lua(&v).ok_or_else(|| {
                script_error(
                    lua,
                    format!(
                        "parameter '{k}': a {} cannot be a parameter value",
                        v.type_name()
                    ),
                )
            })?;
            list.push((k, Override::Value(value)));
        }
        list.sort_by(|a, b| a.0.cmp(&b.0));
    }
    let scope = Scope {
        script: script.to_string(),
        overrides: list,
        declared: Vec::new(),
        first_call: None,
    };
    match lua.app_data_mut::<ParamState>() {
        Some(mut st) => st.scopes.push(scope),
        None => {
            drop(lua.set_app_data(ParamState {
                scopes: vec![scope],
                main: Vec::new(),
            }));
        }
    }
    Ok(())
}

/// Pops a `pge.load` scope; an override it did not declare is reported.
pub(crate) fn pop_scope(lua: &Lua) -> Result<(), OverrideError> {
    let scope = lua
        .app_data_mut::<ParamState>()
        .and_then(|mut st| st.scopes.pop());
    match scope {
        Some(s) => unused_overrides(&s, "pge.load"),
        None => Ok(()),
    }
}

fn unused_overrides(scope: &Scope, source: &'static str) -> Result<(), OverrideError> {
    let unknown: Vec<String> = scope
        .overrides
        .iter()
        .map(|(k, _)| k)
        .filter(|k| !scope.declared.iter().any(|d| d.name == **k))
        .cloned()
        .collect();
    if unknown.is_empty() {
        return Ok(());
    }
    Err(OverrideError::Unknown {
        names: unknown,
        given_with: source,
        declared: scope.declared.iter().map(|d| d.name.clone()).collect(),
    })
}

/// Why a parameter override (`--set NAME=VALUE`, `pge.load(path, {NAME = value})`) was
/// refused.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum OverrideError {
    /// The text given for a numeric parameter is not a finite number.
    #[error("'{0}' is not a number")]
    NotANumber(String),
    /// The text given for a boolean parameter is not one of true/false, 1/0, yes/no, on/off.
    #[error("'{0}' is not a boolean (true or false)")]
    NotABoolean(String),
    /// Overrides name parameters the script does not declare.
    #[error(
        "unknown parameter{} {} given with {given_with}; {}",
        if names.len() > 1 { "s" } else { "" },
        names.join(", "),
        declared_list(declared)
    )]
    Unknown {
        /// The undeclared names, in the order given.
        names: Vec<String>,
        /// How they were given: `--set` or `pge.load`.
        given_with: &'static str,
        /// The parameters the script declares.
        declared: Vec<String>,
    },
}

fn declared_list(declared: &[String]) -> String {
    if declared.is_empty() {
        "the script declares no parameters (pge.params)".to_string()
    } else {
        format!("declared parameters: {}", declared.join(", "))
    }
}

pub(crate) fn register(lua: &Lua, pge: &Table) -> mlua::Result<()> {
    pge.set("params", lua.create_function(declare)?)
}

/// `pge.params{ name = default, other = {default, min =, max =, doc =} }`.
fn declare(lua: &Lua, spec: Table) -> mlua::Result<Table> {
    let mut entries: Vec<(String, Value)> = Vec::new();
    for pair in spec.pairs::<Value, Value>() {
        let (k, v) = pair?;
        let Value::String(k) = k else {
            return Err(script_error(
                lua,
                "pge.params: parameter names must be strings",
            ));
        };
        entries.push((k.to_string_lossy(), v));
    }
    entries.sort_by(|a, b| a.0.cmp(&b.0));
    let out = lua.create_table()?;
    let location = caller_location(lua);
    for (name, v) in entries {
        let info = declaration(lua, &name, &v)?;
        let info = apply_override(lua, info)?;
        if let (Some(x), Some(lo), Some(hi)) = (info.value.as_f64(), info.min, info.max)
            && (x < lo || x > hi)
        {
            return Err(script_error(
                lua,
                format!("parameter '{name}' = {x} is out of its range [{lo}, {hi}]"),
            ));
        }
        out.set(name.as_str(), info.value.clone().into_lua(lua)?)?;
        if let Some(mut st) = lua.app_data_mut::<ParamState>()
            && let Some(scope) = st.scopes.last_mut()
        {
            scope.first_call.get_or_insert_with(|| location.clone());
            scope.declared.retain(|d| d.name != name);
            scope.declared.push(info);
        }
    }
    Ok(out)
}

fn declaration(lua: &Lua, name: &str, v: &Value) -> mlua::Result<ParamInfo> {
    let bad = |what: String| script_error(lua, format!("pge.params: parameter '{name}': {what}"));
    let (default, min, max, doc) = match v {
        Value::Table(t) => {
            let d: Value = match t.raw_get::<Value>(1)? {
                Value::Nil => t.raw_get("default")?,
                d => d,
            };
            let default = ParamValue::from_lua(&d).ok_or_else(|| {
                bad("the default (first entry) must be a number, boolean or string".into())
            })?;
            let num = |key: &str| -> mlua::Result<Option<f64>> {
                match t.raw_get::<Value>(key)? {
                    Value::Nil => Ok(None),
                    Value::Integer(i) => Ok(Some(i as f64)),
                    Value::Number(n) if n.is_finite() => Ok(Some(n)),
                    other => Err(bad(format!(
                        "{key} must be a finite number, not {}",
                        other.type_name()
                    ))),
                }
            };
            let (min, max) = (num("min")?, num("max")?);
            if let (Some(a), Some(b)) = (min, max)
                && a > b
            {
                return Err(bad(format!("min {a} is greater than max {b}")));
            }
            let doc: Option<String> = t.raw_get("doc")?;
            (default, min, max, doc)
        }
        other => (
            ParamValue::from_lua(other)
                .ok_or_else(|| bad(format!("a {} cannot be a parameter", other.type_name())))?,
            None,
            None,
            None,
        ),
    };
    if let ParamValue::Number(n) = default
        && !n.is_finite()
    {
        return Err(bad("the default is not a finite number".into()));
    }
    Ok(ParamInfo {
        name: name.to_string(),
        value: default.clone(),
        default,
        min,
        max,
        doc,
    })
}

fn apply_override(lua: &Lua, mut info: ParamInfo) -> mlua::Result<ParamInfo> {
    let over = lua.app_data_ref::<ParamState>().and_then(|st| {
        st.scopes.last().and_then(|s| {
            s.overrides
                .iter()
                .find(|(k, _)| *k == info.name)
                .map(|(_, o)| o.clone())
        })
    });
    let name = info.name.clone();
    match over {
        None => {}
        Some(Override::Text(text)) => {
            info.value = info
                .default
                .parse_like(&text)
                .map_err(|m| script_error(lua, format!("--set {name}={text}: {m}")))?;
        }
        Some(Override::Value(v)) => {
            let ok = matches!(
                (&info.default, &v),
                (
                    ParamValue::Integer(_) | ParamValue::Number(_),
                    ParamValue::Integer(_) | ParamValue::Number(_)
                ) | (ParamValue::Bool(_), ParamValue::Bool(_))
                    | (ParamValue::Text(_), ParamValue::Text(_))
            );
            if !ok {
                return Err(script_error(
                    lua,
                    format!(
                        "parameter '{name}' expects {}, got {}",
                        info.default.kind(),
                        v.kind()
                    ),
                ));
            }
            info.value = v;
        }
    }
    Ok(info)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn set_values_are_typed_like_the_default() {
        assert_eq!(
            ParamValue::Integer(3).parse_like("5"),
            Ok(ParamValue::Integer(5))
        );
        assert_eq!(
            ParamValue::Integer(3).parse_like("2.5"),
            Ok(ParamValue::Number(2.5))
        );
        assert_eq!(
            ParamValue::Number(1.0)
                .parse_like("x")
                .expect_err("not a number")
                .to_string(),
            "'x' is not a number"
        );
        assert_eq!(
            ParamValue::Bool(false).parse_like("true"),
            Ok(ParamValue::Bool(true))
        );
        assert!(ParamValue::Bool(false).parse_like("maybe").is_err());
        assert_eq!(
            ParamValue::Text("a".into()).parse_like("oak"),
            Ok(ParamValue::Text("oak".into()))
        );
        assert!(ParamValue::Number(1.0).parse_like("nan").is_err());
    }
}
