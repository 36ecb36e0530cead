//! JSON for numbers that may be infinite or NaN. JSON has no such numbers, and serde_json writes
//! them as `null`, which loses which one it was; voxlod writes the strings `"inf"`, `"-inf"` and
//! `"nan"` instead and reads them back. A PSNR of identical images (`+∞`) is the common case.
//!
//! Use [`non_finite`] as `#[serde(with = "voxlod_eval::json::non_finite")]` on an `f64` field, or
//! [`number`] to build a [`serde_json::Value`] by hand.

use serde_json::Value;

/// The JSON value of a number: a JSON number when finite, else `"inf"`, `"-inf"` or `"nan"`.
pub fn number(v: f64) -> Value {
    match non_finite_name(v) {
        Some(name) => Value::String(name.to_owned()),
        None => Value::from(v),
    }
}

fn non_finite_name(v: f64) -> Option<&'static str> {
    if v.is_nan() {
        Some("nan")
    } else if v == f64::INFINITY {
        Some("inf")
    } else if v == f64::NEG_INFINITY {
        Some("-inf")
    } else {
        None
    }
}

/// serde `with` module for `f64` fields that may be non-finite (see the module docs).
pub mod non_finite {
    use serde::{Deserialize, Deserializer, Serializer, de};

    /// Writes a finite value as a number, a non-finite one as `"inf"`, `"-inf"` or `"nan"`.
    pub fn serialize<S: Serializer>(v: &f64, s: S) -> Result<S::Ok, S::Error> {
        match super::non_finite_name(*v) {
            Some(name) => s.serialize_str(name),
            None => s.serialize_f64(*v),
        }
    }

    /// Reads a number, `null` (as NaN), or one of the strings `"inf"`, `"-inf"`, `"nan"`.
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Repr {
            Number(f64),
            Text(String),
            Null(()),
        }
        match Repr::deserialize(d)? {
            Repr::Number(v) => Ok(v),
            Repr::Null(()) => Ok(f64::NAN),
            Repr::Text(t) => match t.as_str() {
                "inf" => Ok(f64::INFINITY),
                "-inf" => Ok(f64::NEG_INFINITY),
                "nan" => Ok(f64::NAN),
                other => Err(de::Error::invalid_value(
                    de::Unexpected::Str(other),
                    &"a number or one of \"inf\", \"-inf\", \"nan\"",
                )),
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use serde::{Deserialize, Serialize};

    use super::*;

    #[derive(Debug, Serialize, Deserialize)]
    struct Wrap {
        #[serde(with = "non_finite")]
        v: f64,
    }

    #[test]
    fn round_trips_every_kind_of_value() {
        for (v, text) in [
            (1.5, r#"{"v":1.5}"#),
            (f64::INFINITY, r#"{"v":"inf"}"#),
            (f64::NEG_INFINITY, r#"{"v":"-inf"}"#),
            (f64::NAN, r#"{"v":"nan"}"#),
        ] {
            assert_eq!(serde_json::to_string(&Wrap { v }).unwrap(), text);
            let back: Wrap = serde_json::from_str(text).unwrap();
            assert!(back.v == v || (back.v.is_nan() && v.is_nan()), "{text}");
            assert_eq!(number(v).to_string(), text[5..text.len() - 1]);
        }
        assert!(serde_json::from_str::<Wrap>(r#"{"v":null}"#).unwrap().v.is_nan());
        let err = serde_json::from_str::<Wrap>(r#"{"v":"infinite"}"#).unwrap_err().to_string();
        assert!(err.contains("data did not match") || err.contains("infinite"), "{err}");
    }
}
