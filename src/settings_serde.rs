//! The serde form of [`Settings`] (feature `serde`): one flat table of the settings a user
//! states, each key the field's name (the contact calibration's ratios as `force_ratio`,
//! `duration_ratio`, `shape_ratio`, `skewness`), a key not given keeping
//! [`Settings::default`]'s value and an unknown key refused by name.
//!
//! The sampled calibration and `flat_top_ratio` are computed (by host-sim's
//! calibration), not stated: they are not keys, and keep their defaults when read. A TOML or
//! JSON number is read as `f64` and rounded to the nearest `f32` (serde's `as` cast). Writing
//! gives every key, so reading back gives the same settings but for those computed fields.

use serde::de::{self, Deserialize, Deserializer, MapAccess, Visitor};
use serde::ser::{Serialize, SerializeStruct, Serializer};

use crate::scene::Settings;

/// Applies `$apply` to the list of keys, each with the path of its field in [`Settings`]: the
/// one place where a key is tied to its field, for reading and writing alike.
macro_rules! with_keys {
    ($apply:ident) => {
        $apply! {
            trigger_sigmas => trigger_sigmas,
            release_sigmas => release_sigmas,
            hold_samples => hold_samples,
            baseline_tau_s => baseline_tau_s,
            stuck_samples => stuck_samples,
            model_sigma => model_sigma,
            confident_error_rate => confident_error_rate,
            out_sigmas => out_sigmas,
            separability_grid => separability_grid,
            shape_tolerance => shape_tolerance,
            force_ratio => contact.force_ratio,
            duration_ratio => contact.duration_ratio,
            shape_ratio => contact.shape_ratio,
            spike_fraction => spike_fraction,
            skewness => contact.skewness,
            skew_tolerance => skew_tolerance,
        }
    };
}

macro_rules! keys {
    ($($key:ident => $($field:ident).+,)*) => {
        /// The keys, in the order an error lists them.
        pub const KEYS: &[&str] = &[$(stringify!($key)),*];

        /// Reads the value of `key` (one of [`KEYS`]) into its field of `s`.
        fn read_value<'de, A: MapAccess<'de>>(
            s: &mut Settings,
            key: &str,
            map: &mut A,
        ) -> Result<(), A::Error> {
            match key {
                $(stringify!($key) => s.$($field).+ = map.next_value()?,)*
                other => return Err(de::Error::unknown_field(other, KEYS)),
            }
            Ok(())
        }

        impl Serialize for Settings {
            /// Every key with its field's value (see the module docs).
            fn serialize<S: Serializer>(&self, ser: S) -> Result<S::Ok, S::Error> {
                let mut st = ser.serialize_struct("Settings", KEYS.len())?;
                $(st.serialize_field(stringify!($key), &self.$($field).+)?;)*
                st.end()
            }
        }
    };
}

with_keys!(keys);

// `visit_map` marks the keys seen in the bits of a `u32`.
const _: () = assert!(KEYS.len() <= 32);

/// A key of the table: its index in [`KEYS`].
struct Key(usize);

impl<'de> Deserialize<'de> for Key {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct KeyVisitor;
        impl Visitor<'_> for KeyVisitor {
            type Value = Key;
            fn expecting(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
                f.write_str("the name of a kernel setting")
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<Key, E> {
                KEYS.iter()
                    .position(|k| *k == v)
                    .map(Key)
                    .ok_or_else(|| E::unknown_field(v, KEYS))
            }
        }
        d.deserialize_identifier(KeyVisitor)
    }
}

impl<'de> Deserialize<'de> for Settings {
    /// A table of any subset of [`KEYS`]; the rest keep [`Settings::default`]. The values are
    /// not checked here: `Scene::new` checks them, naming the field.
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct SettingsVisitor;
        impl<'de> Visitor<'de> for SettingsVisitor {
            type Value = Settings;
            fn expecting(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
                f.write_str("a table of kernel settings")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Settings, A::Error> {
                let mut s = Settings::default();
                let mut seen = 0u32;
                while let Some(Key(i)) = map.next_key()? {
                    let key = KEYS.get(i).copied().unwrap_or_default();
                    if seen & (1 << i) != 0 {
                        return Err(de::Error::duplicate_field(key));
                    }
                    seen |= 1 << i;
                    read_value(&mut s, key, &mut map)?;
                }
                Ok(s)
            }
        }
        d.deserialize_struct("Settings", KEYS, SettingsVisitor)
    }
}
