//! Settings that can be off, as the configuration file and the command line write them: a
//! number, where 0 (or, for some, a negative number) means off. `None` is written as that
//! number, since TOML has no null.

/// `Option<f64>` written as a number, 0 for `None`.
pub(crate) mod at_zero {
    use serde::{Deserialize, Deserializer, Serializer};

    /// `None` as 0.
    pub(crate) fn serialize<S: Serializer>(v: &Option<f64>, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_f64(v.unwrap_or(0.0))
    }

    /// 0 as `None`.
    pub(crate) fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
        let v = f64::deserialize(d)?;
        Ok((v != 0.0).then_some(v))
    }
}

/// `Option<f64>` written as a number, -1 for `None` (any negative number reads as `None`).
pub(crate) mod when_negative {
    use serde::{Deserialize, Deserializer, Serializer};

    /// `None` as -1.
    pub(crate) fn serialize<S: Serializer>(v: &Option<f64>, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_f64(v.unwrap_or(-1.0))
    }

    /// A negative number as `None`.
    pub(crate) fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
        let v = f64::deserialize(d)?;
        Ok((v >= 0.0 || v.is_nan()).then_some(v))
    }
}

#[cfg(test)]
mod tests {
    use serde::{Deserialize, Serialize};

    #[derive(Debug, PartialEq, Serialize, Deserialize)]
    struct Both {
        #[serde(with = "super::at_zero")]
        zero: Option<f64>,
        #[serde(with = "super::when_negative")]
        negative: Option<f64>,
    }

    #[test]
    fn off_is_written_as_a_number_and_read_back() {
        let off = Both {
            zero: None,
            negative: None,
        };
        let text = toml::to_string(&off).unwrap();
        assert_eq!(text, "zero = 0.0\nnegative = -1.0\n");
        assert_eq!(toml::from_str::<Both>(&text).unwrap(), off);
        let on: Both = toml::from_str("zero = 0.6\nnegative = 0.0").unwrap();
        assert_eq!((on.zero, on.negative), (Some(0.6), Some(0.0)));
        let off: Both = toml::from_str("zero = 0\nnegative = -3").unwrap();
        assert_eq!((off.zero, off.negative), (None, None));
    }
}
