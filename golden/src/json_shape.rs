//! The shape of a JSON document against a reference: serde accepts a JSON array for a struct
//! (its fields by position), so `[500]` would silently be a configuration whose first field is
//! 500. Every reader of a struct-shaped document checks its parsed [`Value`] with
//! [`check_shape`] first: wherever the reference (the serialised default, or the serialised
//! typed document) is an object, the input must be an object.

use serde::de::DeserializeOwned;
use serde::Serialize;
use serde_json::Value;

/// Parses `text` as a `T` whose shape is that of `default` (its serialised form, [`check_shape`]):
/// the reader of a configuration whose absent fields keep their defaults. The typed parse reads
/// the text itself, so its errors keep their line and column.
pub fn parse_shaped<T: DeserializeOwned + Serialize>(text: &str, default: &T) -> Result<T, String> {
    let value: Value = serde_json::from_str(text).map_err(|e| e.to_string())?;
    let reference = serde_json::to_value(default).map_err(|e| e.to_string())?;
    check_shape(&value, &reference)?;
    serde_json::from_str(text).map_err(|e| e.to_string())
}

/// Checks that `input` is an object wherever `reference` is one, recursing into the fields (and
/// array elements, pairwise) both have. The error names the field path (`dram`,
/// `sort_core.merge[3]`; nothing for the document itself) and what was found, e.g.
/// `dram: expected an object, found an array`.
pub fn check_shape(input: &Value, reference: &Value) -> Result<(), String> {
    check_at(input, reference, &mut String::new())
}

fn kind(v: &Value) -> &'static str {
    match v {
        Value::Null => "null",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "an array",
        Value::Object(_) => "an object",
    }
}

fn check_at(input: &Value, reference: &Value, path: &mut String) -> Result<(), String> {
    match (input, reference) {
        (Value::Object(i), Value::Object(r)) => {
            for (key, iv) in i {
                if let Some(rv) = r.get(key) {
                    let len = path.len();
                    if !path.is_empty() {
                        path.push('.');
                    }
                    path.push_str(key);
                    check_at(iv, rv, path)?;
                    path.truncate(len);
                }
            }
            Ok(())
        }
        (_, Value::Object(_)) => {
            let found = kind(input);
            if path.is_empty() {
                Err(format!("expected an object, found {found}"))
            } else {
                Err(format!("{path}: expected an object, found {found}"))
            }
        }
        (Value::Array(i), Value::Array(r)) => {
            for (n, (iv, rv)) in i.iter().zip(r).enumerate() {
                let len = path.len();
                path.push_str(&format!("[{n}]"));
                check_at(iv, rv, path)?;
                path.truncate(len);
            }
            Ok(())
        }
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    /// Arrays (or any non-object) where the reference has an object are refused with the path;
    /// fields the reference lacks, and non-object references, are left to the typed reader.
    #[test]
    fn an_array_for_an_object_is_named_by_its_path() {
        let reference = json!({"clock_mhz": 1.0, "dram": {"name": "x", "channels": 4}, "l": [{"a": 1}]});
        assert_eq!(check_shape(&json!([500]), &reference).unwrap_err(), "expected an object, found an array");
        assert_eq!(check_shape(&json!([]), &reference).unwrap_err(), "expected an object, found an array");
        assert_eq!(check_shape(&json!(5), &reference).unwrap_err(), "expected an object, found a number");
        assert_eq!(
            check_shape(&json!({"dram": ["x", 2]}), &reference).unwrap_err(),
            "dram: expected an object, found an array"
        );
        assert_eq!(
            check_shape(&json!({"l": [{"a": 1}, [2]]}), &json!({"l": [{"a": 1}, {"a": 2}]})).unwrap_err(),
            "l[1]: expected an object, found an array"
        );
        check_shape(&json!({"dram": {"channels": 2}, "other": [1]}), &reference).unwrap();
        check_shape(&json!({"clock_mhz": [1]}), &reference).unwrap();
        check_shape(&json!({}), &reference).unwrap();
    }

    /// The engine configuration's reader refuses a document that is an array (`[]` was the
    /// default configuration, `[4]` set the first field) naming the file.
    #[test]
    fn the_engine_configuration_must_be_an_object() {
        let dir = std::env::temp_dir().join(format!("neo-json-shape-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("e.json");
        for text in ["[]", "[4]"] {
            std::fs::write(&p, text).unwrap();
            let e = crate::engine::EngineConfig::from_json_file(&p).unwrap_err().to_string();
            assert!(e.contains("e.json") && e.contains("expected an object, found an array"), "{e}");
        }
        std::fs::write(&p, r#"{"sort_cores": 8}"#).unwrap();
        assert_eq!(crate::engine::EngineConfig::from_json_file(&p).unwrap().sort_cores, 8);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
