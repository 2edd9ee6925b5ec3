//! Unit enums read from their names in TOML files, with a message that says
//! what was wanted when the value is not a string: serde's own for an enum
//! given a number, "wanted string or table", names neither the choices nor
//! that a string was expected.

use serde::Deserialize;
use serde::de::{self, Deserializer, Visitor};
use std::fmt;
use std::marker::PhantomData;

/// Reads a `T` (a unit enum deriving `Deserialize`) from its name, one of
/// `names`; anything but a string is refused as "expected a string: one of
/// ...". An unknown name keeps serde's message, which lists the names.
pub fn by_name<'de, D, T>(d: D, names: &'static [&'static str]) -> Result<T, D::Error>
where
    D: Deserializer<'de>,
    T: Deserialize<'de>,
{
    struct Named<T>(&'static [&'static str], PhantomData<T>);
    impl<'de, T: Deserialize<'de>> Visitor<'de> for Named<T> {
        type Value = T;
        fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
            write!(f, "a string: one of {}", self.0.join(", "))
        }
        fn visit_str<E: de::Error>(self, v: &str) -> Result<T, E> {
            T::deserialize(de::value::StrDeserializer::<E>::new(v))
        }
    }
    d.deserialize_any(Named(names, PhantomData))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, PartialEq, Deserialize)]
    #[serde(rename_all = "snake_case")]
    enum Pin {
        None,
        TopEdge,
    }

    #[derive(Debug, Deserialize)]
    struct Table {
        #[serde(deserialize_with = "pin")]
        pin: Pin,
    }

    fn pin<'de, D: Deserializer<'de>>(d: D) -> Result<Pin, D::Error> {
        by_name(d, &["none", "top_edge"])
    }

    #[test]
    fn a_name_reads_and_anything_else_says_what_was_wanted() {
        let t: Table = toml::from_str("pin = \"top_edge\"").unwrap();
        assert_eq!(t.pin, Pin::TopEdge);
        let e = toml::from_str::<Table>("pin = 3").unwrap_err().to_string();
        assert!(
            e.contains("expected a string: one of none, top_edge"),
            "{e}"
        );
        let e = toml::from_str::<Table>("pin = \"edge\"")
            .unwrap_err()
            .to_string();
        assert!(e.contains("unknown variant `edge`"), "{e}");
        assert!(Pin::None != Pin::TopEdge);
    }
}
