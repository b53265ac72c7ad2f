//! The pieces of USD's text form (`.usda`): numbers, strings, names, and JSON values as
//! `customData` dictionaries. Floats are written as the shortest text that reads back to the
//! same `f32` (zmij), so a layer's bytes depend on the numbers alone.

use std::fmt::Write;

use serde_json::Value as JsonValue;

/// A layer's text being written, with the indentation of the current scope.
pub(super) struct Text {
    pub(super) out: String,
    depth: usize,
    floats: zmij::Buffer,
    ints: itoa::Buffer,
}

impl Text {
    pub(super) fn with_capacity(bytes: usize) -> Text {
        Text {
            out: String::with_capacity(bytes),
            depth: 0,
            floats: zmij::Buffer::new(),
            ints: itoa::Buffer::new(),
        }
    }

    /// Starts a line at the current indentation.
    pub(super) fn line(&mut self) -> &mut String {
        self.out.push('\n');
        for _ in 0..self.depth {
            self.out.push_str("    ");
        }
        &mut self.out
    }

    /// A line of `text`.
    pub(super) fn put(&mut self, text: &str) {
        self.line().push_str(text);
    }

    /// The current indentation.
    pub(super) fn depth(&self) -> usize {
        self.depth
    }

    /// Sets the indentation (a piece formatted on its own).
    pub(super) fn set_depth(&mut self, depth: usize) {
        self.depth = depth;
    }

    /// One level deeper (after a line that opens a scope).
    pub(super) fn depth_in(&mut self) {
        self.depth += 1;
    }

    /// A line `text` and `{` on the next, one level deeper.
    pub(super) fn open(&mut self, text: &str, opening: &str) {
        if !text.is_empty() {
            self.put(text);
        }
        self.put(opening);
        self.depth += 1;
    }

    /// Back one level, and the closing line.
    pub(super) fn close(&mut self, closing: &str) {
        self.depth -= 1;
        self.put(closing);
    }

    /// A finite float; a non-finite one (the model's validation rejects them) as `nan` or
    /// `inf`, which USD reads.
    pub(super) fn float(&mut self, v: f32) {
        if v.is_finite() {
            self.out.push_str(self.floats.format_finite(v));
        } else if v.is_nan() {
            self.out.push_str("nan");
        } else if v > 0.0 {
            self.out.push_str("inf");
        } else {
            self.out.push_str("-inf");
        }
    }

    pub(super) fn double(&mut self, v: f64) {
        if v.is_finite() {
            self.out.push_str(self.floats.format_finite(v));
        } else {
            self.out.push_str(if v.is_nan() { "nan" } else { "inf" });
        }
    }

    pub(super) fn int(&mut self, v: impl itoa::Integer) {
        self.out.push_str(self.ints.format(v));
    }

    /// `(a, b, ...)` of floats.
    pub(super) fn tuple(&mut self, values: &[f32]) {
        self.out.push('(');
        for (k, &v) in values.iter().enumerate() {
            if k > 0 {
                self.out.push_str(", ");
            }
            self.float(v);
        }
        self.out.push(')');
    }

    /// `[item, item, ...]`, each item written by `item`.
    pub(super) fn array<T>(&mut self, items: &[T], mut item: impl FnMut(&mut Text, &T)) {
        self.out.push('[');
        for (k, v) in items.iter().enumerate() {
            if k > 0 {
                self.out.push_str(", ");
            }
            item(self, v);
        }
        self.out.push(']');
    }

    /// A quoted string.
    pub(super) fn string(&mut self, s: &str) {
        quote(&mut self.out, s);
    }

    /// `dictionary "key" = { ... }` of a JSON object's entries, or the one typed entry a
    /// JSON value is (see [`Text::json_entry`]).
    pub(super) fn json_entries(&mut self, map: &serde_json::Map<String, JsonValue>) {
        for (key, value) in map {
            self.json_entry(key, value);
        }
    }

    /// One entry of a `customData` dictionary for a JSON value: a number as `int64`,
    /// `uint64` or `double`, a string, a bool, an object as a `dictionary`, an array of
    /// numbers, strings or bools as the typed array, any other array as a dictionary keyed
    /// `"0"`, `"1"`, ...; `null` as the string `"null"` (a dictionary has no null).
    pub(super) fn json_entry(&mut self, key: &str, value: &JsonValue) {
        let typed = |t: &mut Text, ty: &str| {
            let l = t.line();
            l.push_str(ty);
            l.push(' ');
            quote(l, key);
            l.push_str(" = ");
        };
        match value {
            JsonValue::Null => {
                typed(self, "string");
                self.string("null");
            }
            JsonValue::Bool(b) => {
                typed(self, "bool");
                self.out.push(if *b { '1' } else { '0' });
            }
            JsonValue::Number(n) => {
                if let Some(i) = n.as_i64() {
                    typed(self, "int64");
                    self.int(i);
                } else if let Some(u) = n.as_u64() {
                    typed(self, "uint64");
                    self.int(u);
                } else {
                    typed(self, "double");
                    self.double(n.as_f64().unwrap_or(f64::NAN));
                }
            }
            JsonValue::String(s) => {
                typed(self, "string");
                self.string(s);
            }
            JsonValue::Object(map) => {
                typed(self, "dictionary");
                self.out.push('{');
                self.depth += 1;
                self.json_entries(map);
                self.close("}");
            }
            JsonValue::Array(items) => {
                if !items.is_empty() && items.iter().all(|v| v.is_i64()) {
                    typed(self, "int64[]");
                    self.array(items, |t, v| t.int(v.as_i64().unwrap_or(0)));
                } else if !items.is_empty() && items.iter().all(JsonValue::is_number) {
                    typed(self, "double[]");
                    self.array(items, |t, v| t.double(v.as_f64().unwrap_or(f64::NAN)));
                } else if !items.is_empty() && items.iter().all(JsonValue::is_string) {
                    typed(self, "string[]");
                    self.array(items, |t, v| t.string(v.as_str().unwrap_or("")));
                } else if !items.is_empty() && items.iter().all(JsonValue::is_boolean) {
                    typed(self, "bool[]");
                    self.array(items, |t, v| {
                        t.out
                            .push(if v.as_bool() == Some(true) { '1' } else { '0' });
                    });
                } else {
                    typed(self, "dictionary");
                    self.out.push('{');
                    self.depth += 1;
                    for (k, v) in items.iter().enumerate() {
                        self.json_entry(&k.to_string(), v);
                    }
                    self.close("}");
                }
            }
        }
    }
}

/// `s` quoted for a `.usda`: backslash, quote and control characters escaped.
pub(super) fn quote(out: &mut String, s: &str) {
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            c if (c as u32) < 0x20 || c == '\u{7f}' => {
                let _ = write!(out, "\\x{:02x}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
}

/// `name` as a prim name: letters, digits and `_`, not starting with a digit (`_` for an
/// empty name).
pub(super) fn identifier(name: &str) -> String {
    let mut id: String = name
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    if id.is_empty() || id.starts_with(|c: char| c.is_ascii_digit()) {
        id.insert(0, '_');
    }
    id
}

/// Names made unique among siblings: a name taken before gets `_2`, `_3`, ...
#[derive(Default)]
pub(super) struct Names(std::collections::HashSet<String>);

impl Names {
    /// The identifier for `name`, unique among those given before.
    pub(super) fn unique(&mut self, name: &str) -> String {
        let base = identifier(name);
        let mut id = base.clone();
        let mut k = 2;
        while !self.0.insert(id.clone()) {
            id = format!("{base}_{k}");
            k += 1;
        }
        id
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_identifiers_and_unique() {
        let mut names = Names::default();
        assert_eq!(names.unique("oak/0"), "oak_0");
        assert_eq!(names.unique("oak 0"), "oak_0_2");
        assert_eq!(names.unique("oak/0"), "oak_0_3");
        assert_eq!(names.unique("3 leaves"), "_3_leaves");
        assert_eq!(names.unique(""), "_");
    }

    #[test]
    fn strings_are_escaped() {
        let mut s = String::new();
        quote(&mut s, "a \"b\"\\\n\u{1}é");
        assert_eq!(s, r#""a \"b\"\\\n\x01é""#);
    }

    #[test]
    fn floats_are_the_shortest_round_trip() {
        let mut t = Text::with_capacity(0);
        t.tuple(&[0.1, -2.5, 1.0e-30, 3.0]);
        let parsed: Vec<f32> = t.out[1..t.out.len() - 1]
            .split(", ")
            .map(|v| v.parse().expect("a float"))
            .collect();
        assert_eq!(parsed, [0.1, -2.5, 1.0e-30, 3.0]);
        assert!(t.out.starts_with("(0.1, -2.5, "), "{}", t.out);
    }

    #[test]
    fn json_becomes_typed_dictionary_entries() {
        let mut t = Text::with_capacity(0);
        let value = serde_json::json!({
            "n": 3, "x": 0.5, "s": "a", "b": true, "ints": [1, 2], "mixed": [1, "a"],
            "obj": {"k": null}, "big": u64::MAX
        });
        t.json_entries(value.as_object().expect("an object"));
        for line in [
            r#"int64 "n" = 3"#,
            r#"double "x" = 0.5"#,
            r#"string "s" = "a""#,
            r#"bool "b" = 1"#,
            r#"int64[] "ints" = [1, 2]"#,
            r#"dictionary "mixed" = {"#,
            r#"    int64 "0" = 1"#,
            r#"    string "1" = "a""#,
            r#"    string "k" = "null""#,
            r#"uint64 "big" = 18446744073709551615"#,
        ] {
            assert!(t.out.contains(line), "{line} in {}", t.out);
        }
    }
}
