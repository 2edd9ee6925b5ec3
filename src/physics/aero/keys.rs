//! The `[aero]` keys a leaf file sets, as read: each law declares its own
//! ([`Key`] lists in its `coefficients` file) and builds its coefficients
//! from them; this file only holds what was set. The order leaf files write
//! them in is every law's keys in turn ([`super::law::all_keys`]).

/// What a key's value is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum KeyKind {
    /// A number (TOML float or integer).
    Number,
    /// A flag (TOML boolean).
    Flag,
}

/// One key of a law's `[aero]` table.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Key {
    /// The key as leaf files spell it.
    pub name: &'static str,
    /// Number or flag.
    pub kind: KeyKind,
}

impl Key {
    /// A numeric key.
    pub const fn number(name: &'static str) -> Key {
        Key {
            name,
            kind: KeyKind::Number,
        }
    }

    /// A boolean key.
    pub const fn flag(name: &'static str) -> Key {
        Key {
            name,
            kind: KeyKind::Flag,
        }
    }
}

/// A key's value as read.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum KeyValue {
    /// A number.
    Number(f64),
    /// A flag.
    Flag(bool),
}

/// The keys set in an `[aero]` table (equal whatever the order they were
/// set in).
#[derive(Clone, Debug, Default)]
pub struct AeroKeys(Vec<(Key, KeyValue)>);

impl PartialEq for AeroKeys {
    fn eq(&self, other: &AeroKeys) -> bool {
        self.0.len() == other.0.len() && self.0.iter().all(|(k, v)| other.get(k.name) == Some(*v))
    }
}

impl AeroKeys {
    /// Sets `key` (replacing a value it had).
    pub fn set(&mut self, key: Key, value: KeyValue) {
        match self.0.iter().position(|(k, _)| k.name == key.name) {
            Some(at) => self.0[at].1 = value,
            None => self.0.push((key, value)),
        }
    }

    /// The value set for `name`, if any.
    pub fn get(&self, name: &str) -> Option<KeyValue> {
        self.0.iter().find(|(k, _)| k.name == name).map(|(_, v)| *v)
    }

    /// Removes `name`.
    pub fn remove(&mut self, name: &str) {
        self.0.retain(|(k, _)| k.name != name);
    }

    /// The number set for `name`, if any.
    pub fn number(&self, name: &str) -> Option<f64> {
        self.0.iter().find_map(|(k, v)| match v {
            KeyValue::Number(x) if k.name == name => Some(*x),
            _ => None,
        })
    }

    /// The flag set for `name`, if any.
    pub fn flag(&self, name: &str) -> Option<bool> {
        self.0.iter().find_map(|(k, v)| match v {
            KeyValue::Flag(b) if k.name == name => Some(*b),
            _ => None,
        })
    }

    /// Every key set, with its value, in the order they were set.
    pub fn iter(&self) -> impl Iterator<Item = (Key, KeyValue)> + '_ {
        self.0.iter().copied()
    }
}
