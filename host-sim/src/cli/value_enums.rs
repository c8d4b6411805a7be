//! The command-line form of the library's enums: clap's `ValueEnum` from each enum's list
//! (`ALL`), name (`as_str`) and one-line help (`about`), so the layers below know no clap.

use clap::ValueEnum;
use clap::builder::PossibleValue;

use crate::report::impact_row::{LawName, MethodName};
use crate::score::caving::Profile;
use crate::score::evaluate::BackendChoice;

/// `ValueEnum` for enums that carry `ALL`, `as_str()` and `about()`.
macro_rules! value_enum {
    ($($name:ty),+) => {$(
        impl ValueEnum for $name {
            fn value_variants<'a>() -> &'a [Self] {
                &Self::ALL
            }

            fn to_possible_value(&self) -> Option<PossibleValue> {
                Some(PossibleValue::new(self.as_str()).help(self.about()))
            }
        }
    )+};
}

value_enum!(LawName, MethodName, Profile, BackendChoice);

#[cfg(test)]
mod tests {
    use super::*;

    /// Every name parses back to its value through clap, case-insensitively, and the library's
    /// own parsers agree with clap on every name.
    #[test]
    fn names_read_back() {
        fn check<T: ValueEnum + PartialEq + std::fmt::Debug>(all: &[T], name: fn(&T) -> &str) {
            for v in all {
                assert_eq!(T::from_str(name(v), false).as_ref(), Ok(v));
                assert_eq!(
                    T::from_str(&name(v).to_ascii_uppercase(), true).as_ref(),
                    Ok(v)
                );
            }
            assert!(T::from_str("no-such-name", true).is_err());
        }
        check(&LawName::ALL, |v| v.as_str());
        check(&MethodName::ALL, |v| v.as_str());
        check(&Profile::ALL, |v| v.as_str());
        check(&BackendChoice::ALL, |v| v.as_str());
        for l in LawName::ALL {
            assert_eq!(LawName::parse(&l.as_str().replace('-', "_")), Ok(l));
        }
        for m in MethodName::ALL {
            assert_eq!(MethodName::parse(m.as_str()), Ok(m));
        }
    }

    /// The names are the ones the scene files and batch files use (written out here, not
    /// taken from the enums).
    #[test]
    fn names_are_the_documented_ones() {
        let names = |v: Vec<PossibleValue>| -> Vec<String> {
            v.iter().map(|p| p.get_name().to_string()).collect()
        };
        let laws = LawName::ALL.iter().filter_map(ValueEnum::to_possible_value);
        assert_eq!(
            names(laws.collect()),
            [
                "hertz",
                "adams",
                "hunt-crossley",
                "lankarani-nikravesh",
                "flores",
                "gonthier",
                "tsuji"
            ]
        );
        let profiles = Profile::ALL.iter().filter_map(ValueEnum::to_possible_value);
        assert_eq!(names(profiles.collect()), ["step", "ramp"]);
        for p in Profile::ALL {
            let json = serde_json::to_string(&p).expect("serialises");
            assert_eq!(
                json,
                format!("{:?}", p.as_str()),
                "the [caving] table's name"
            );
        }
    }
}
