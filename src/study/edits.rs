//! Edits of the case by a study: each run is the base case, then the variant's `set`, then the
//! refinement's `set`, then the variant's `refinement_set[level]` if it has one (a later
//! setting of the same path wins), applied to the case's TOML table before it is validated
//! ([`Scene::load_edited`]).
//!
//! A path is dotted: a segment that is a number indexes an array (of tables: `mesh.0` is the
//! first `[[mesh]]`), any other names a key of a table. The value replaces what is there (a
//! table value replaces a whole table). A missing key may be created in a table (with tables
//! created for the rest of the path: `"steps.count" = 4` works on a case without `[steps]`);
//! the case parser then validates it like any key. A path that cannot lead anywhere is an error
//! naming the study key and the path: an index past the end of an array or into a missing key,
//! a name used on an array, a path through a number or a string. Write dotted paths in quotes:
//! TOML reads `mesh.0.n_circ = 2` unquoted as nested tables, which this refuses with a hint.
//!
//! [`Scene::load_edited`]: crate::case::Scene::load_edited

use super::file::{RefinementSpec, VariantSpec};

/// The edits of one run, in order: the variant's, then the refinement's; each with the study
/// key it comes from.
pub(super) fn edits<'a>(
    v: usize,
    variant: &'a VariantSpec,
    level: usize,
    refinement: &'a RefinementSpec,
) -> Vec<(String, &'a str, &'a toml::Value)> {
    let mut out = Vec::new();
    let mut tables = vec![
        (format!("variant[{v}].set"), &variant.set),
        (format!("refinement[{level}].set"), &refinement.set),
    ];
    if let Some(per_level) = variant.refinement_set.get(level) {
        tables.push((format!("variant[{v}].refinement_set[{level}]"), per_level));
    }
    for (key, table) in tables {
        for (path, value) in table {
            out.push((key.clone(), path.as_str(), value));
        }
    }
    out
}

/// Applies edits `(study key, dotted path, value)` to a case table, in order.
pub(super) fn apply_sets(
    case: &mut toml::Table,
    edits: &[(String, &str, &toml::Value)],
) -> std::result::Result<(), String> {
    for (key, path, value) in edits {
        set_path(case, path, (*value).clone()).map_err(|m| format!("{key}.\"{path}\": {m}"))?;
    }
    Ok(())
}

/// Sets `value` at the dotted `path` of `table` (see the module docs for what may be created).
pub fn set_path(
    table: &mut toml::Table,
    path: &str,
    value: toml::Value,
) -> std::result::Result<(), String> {
    let segments: Vec<&str> = path.split('.').collect();
    if segments.iter().any(|s| s.trim().is_empty()) {
        return Err("not a dotted path (an empty segment)".into());
    }
    set_in_table(table, &segments, 0, value)
}

/// An array index segment.
fn index(segment: &str) -> Option<usize> {
    segment.parse().ok()
}

/// [`set_path`] from segment `i` on, in the table at `segments[..i]`.
fn set_in_table(
    table: &mut toml::Table,
    segments: &[&str],
    i: usize,
    value: toml::Value,
) -> std::result::Result<(), String> {
    let seg = segments[i];
    let at = segments[..=i].join(".");
    if index(seg).is_some() {
        let name = if i == 0 {
            "the case".to_string()
        } else {
            format!("'{}'", segments[..i].join("."))
        };
        return Err(format!(
            "{name} is a table, not an array: '{seg}' cannot index it"
        ));
    }
    if i + 1 == segments.len() {
        if let (Some(toml::Value::Array(_)), toml::Value::Table(_)) = (table.get(seg), &value) {
            return Err(format!(
                "a table would replace the array '{at}' (write dotted paths in quotes: \
                 \"{at}.0.key\" = value)"
            ));
        }
        table.insert(seg.to_string(), value);
        return Ok(());
    }
    if !table.contains_key(seg) {
        if let Some(k) = index(segments[i + 1]) {
            return Err(format!("no '{at}' in the case to index with {k}"));
        }
        table.insert(seg.to_string(), toml::Value::Table(toml::Table::new()));
    }
    let next = table.get_mut(seg).expect("present or just inserted");
    set_in_value(next, segments, i + 1, value)
}

/// [`set_path`] from segment `i` on, in the value at `segments[..i]`.
fn set_in_value(
    here: &mut toml::Value,
    segments: &[&str],
    i: usize,
    value: toml::Value,
) -> std::result::Result<(), String> {
    let at = segments[..i].join(".");
    match here {
        toml::Value::Table(t) => set_in_table(t, segments, i, value),
        toml::Value::Array(items) => {
            let Some(k) = index(segments[i]) else {
                return Err(format!(
                    "'{at}' is an array: the next segment must be an index, not '{}'",
                    segments[i]
                ));
            };
            let n = items.len();
            let Some(item) = items.get_mut(k) else {
                let entries = if n == 1 { "entry" } else { "entries" };
                return Err(format!("'{at}' has {n} {entries}, no index {k}"));
            };
            if i + 1 == segments.len() {
                *item = value;
                Ok(())
            } else {
                set_in_value(item, segments, i + 1, value)
            }
        }
        other => Err(format!(
            "'{at}' is a value ({}), not a table",
            other.type_str()
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn case() -> toml::Table {
        toml::from_str(
            r#"
name = "s"
[[mesh]]
element = "hex20"
n_circ = 2
[[mesh]]
element = "hex8"
[steps]
count = 1
"#,
        )
        .unwrap()
    }

    fn set(path: &str, v: toml::Value) -> std::result::Result<toml::Table, String> {
        let mut t = case();
        set_path(&mut t, path, v)?;
        Ok(t)
    }

    #[test]
    fn paths_reach_array_entries_and_tables() {
        let t = set("mesh.1.n_circ", 3.into()).unwrap();
        assert_eq!(t["mesh"][1]["n_circ"].as_integer(), Some(3));
        assert_eq!(t["mesh"][0]["n_circ"].as_integer(), Some(2));
        let t = set("mesh.0.element", "hex27".into()).unwrap();
        assert_eq!(t["mesh"][0]["element"].as_str(), Some("hex27"));
        let t = set("steps.count", 4.into()).unwrap();
        assert_eq!(t["steps"]["count"].as_integer(), Some(4));
        // Missing keys are created, tables too: the case parser validates them.
        let t = set("newton.max_it", 2.into()).unwrap();
        assert_eq!(t["newton"]["max_it"].as_integer(), Some(2));
        let t = set("mesh.0.n_rad", 2.into()).unwrap();
        assert_eq!(t["mesh"][0]["n_rad"].as_integer(), Some(2));
        let t = set("name", "other".into()).unwrap();
        assert_eq!(t["name"].as_str(), Some("other"));
    }

    #[test]
    fn impossible_paths_are_named() {
        let e = set("mesh.2.n_circ", 3.into()).unwrap_err();
        assert_eq!(e, "'mesh' has 2 entries, no index 2");
        let e = set("meshes.0.n_circ", 3.into()).unwrap_err();
        assert!(e.contains("no 'meshes'"), "{e}");
        let e = set("mesh.first.n_circ", 3.into()).unwrap_err();
        assert!(e.contains("'mesh' is an array"), "{e}");
        let e = set("name.x", 3.into()).unwrap_err();
        assert!(e.contains("'name' is a value (string)"), "{e}");
        let e = set("mesh.0.n_circ.x", 3.into()).unwrap_err();
        assert!(e.contains("'mesh.0.n_circ' is a value (integer)"), "{e}");
        let e = set("steps.0", 3.into()).unwrap_err();
        assert!(e.contains("'steps' is a table"), "{e}");
        let e = set("mesh..x", 3.into()).unwrap_err();
        assert!(e.contains("empty segment"), "{e}");
        let nested: toml::Value =
            toml::from_str::<toml::Table>("a = { \"0\" = { n = 1 } }").unwrap()["a"].clone();
        let e = set("mesh", nested).unwrap_err();
        assert!(e.contains("in quotes"), "{e}");
    }

    #[test]
    fn later_edits_win_and_errors_name_the_key() {
        let mut t = case();
        let (a, b) = (toml::Value::from(3), toml::Value::from(4));
        let edits = vec![
            ("variant[0].set".to_string(), "mesh.0.n_circ", &a),
            ("refinement[1].set".to_string(), "mesh.0.n_circ", &b),
        ];
        apply_sets(&mut t, &edits).unwrap();
        assert_eq!(t["mesh"][0]["n_circ"].as_integer(), Some(4));
        let bad = vec![("refinement[1].set".to_string(), "mesh.7.n_circ", &a)];
        let e = apply_sets(&mut t, &bad).unwrap_err();
        assert!(
            e.starts_with("refinement[1].set.\"mesh.7.n_circ\": 'mesh'"),
            "{e}"
        );
    }
}
