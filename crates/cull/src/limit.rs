//! Serde codec of a limit that may be infinite (an `f64` that `inf` switches off, such as the crystal grouping's
//! `max_expanse`), for `#[serde(with = "cull::limit")]`.
//!
//! JSON has no number for infinity: serde_json writes `null`, which does not read back as an `f64`, so a tile plan or
//! an exported hierarchy holding such a limit could not be read again. In human-readable formats (JSON, TOML) an
//! infinite value is therefore written as the string `"inf"` (`"-inf"`), and read from a number, from those strings or
//! from TOML's own `inf`; every finite value is written as the number it is. Binary formats (the `.tch`'s postcard)
//! keep the plain `f64`, so the files' bytes do not change.

use serde::de::{self, Deserializer, Visitor};
use serde::{Deserialize, Serializer};

/// Writes `v`: an infinite value as `"inf"` or `"-inf"` in a human-readable format, any other as a number.
pub fn serialize<S: Serializer>(v: &f64, s: S) -> Result<S::Ok, S::Error> {
    if s.is_human_readable() && v.is_infinite() {
        s.serialize_str(if *v > 0.0 { "inf" } else { "-inf" })
    } else {
        s.serialize_f64(*v)
    }
}

/// Reads a number, or in a human-readable format also `"inf"`, `"+inf"`, `"infinity"` or `"-inf"` (any case).
pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    if !d.is_human_readable() {
        return f64::deserialize(d);
    }
    struct Limit;
    impl Visitor<'_> for Limit {
        type Value = f64;
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str("a number or \"inf\"")
        }
        fn visit_f64<E: de::Error>(self, v: f64) -> Result<f64, E> {
            Ok(v)
        }
        fn visit_i64<E: de::Error>(self, v: i64) -> Result<f64, E> {
            Ok(v as f64)
        }
        fn visit_u64<E: de::Error>(self, v: u64) -> Result<f64, E> {
            Ok(v as f64)
        }
        fn visit_str<E: de::Error>(self, v: &str) -> Result<f64, E> {
            match v.to_ascii_lowercase().as_str() {
                "inf" | "+inf" | "infinity" | "+infinity" => Ok(f64::INFINITY),
                "-inf" | "-infinity" => Ok(f64::NEG_INFINITY),
                _ => Err(E::invalid_value(de::Unexpected::Str(v), &self)),
            }
        }
    }
    d.deserialize_any(Limit)
}

#[cfg(test)]
mod tests {
    use serde::{Deserialize, Serialize};

    #[derive(Debug, PartialEq, Serialize, Deserialize)]
    struct Holder {
        #[serde(with = "super")]
        limit: f64,
    }

    #[test]
    fn infinity_round_trips_through_json_and_postcard() {
        for limit in [f64::INFINITY, f64::NEG_INFINITY, 0.25, 3.0, f64::MAX, -0.0] {
            let h = Holder { limit };
            let json = serde_json::to_string(&h).expect("json");
            assert_eq!(serde_json::from_str::<Holder>(&json).expect("read back"), h, "{json}");
            let bytes = postcard::to_allocvec(&h).expect("postcard");
            assert_eq!(
                bytes,
                postcard::to_allocvec(&limit).expect("a plain f64"),
                "binary form unchanged"
            );
            assert_eq!(postcard::from_bytes::<Holder>(&bytes).expect("read back"), h);
        }
        assert_eq!(
            serde_json::to_string(&Holder { limit: f64::INFINITY }).expect("json"),
            r#"{"limit":"inf"}"#
        );
        assert_eq!(
            serde_json::from_str::<Holder>(r#"{"limit":3}"#)
                .expect("an integer")
                .limit,
            3.0
        );
        assert_eq!(
            serde_json::from_str::<Holder>(r#"{"limit":"Infinity"}"#)
                .expect("a word")
                .limit,
            f64::INFINITY
        );
        let e = serde_json::from_str::<Holder>(r#"{"limit":"lots"}"#).expect_err("not a limit");
        assert!(e.to_string().contains(r#"expected a number or "inf""#), "{e}");
        assert!(serde_json::from_str::<Holder>(r#"{"limit":null}"#).is_err());
    }
}
