//! Validation of input files: a collector of bad fields, so one pass over a scenario or config
//! reports every bad field at once, each with its name, the value found and
//! what is allowed. Every crate's loaders use it; the crate's own error type adds the file.

use thiserror::Error;

/// One bad field: where, what was found, what is allowed.
#[derive(Debug, Clone, PartialEq)]
pub struct Problem {
    pub field: String,
    pub value: String,
    pub allowed: String,
}

impl std::fmt::Display for Problem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "field {} = {}: allowed {}", self.field, self.value, self.allowed)
    }
}

/// Every bad field found, as one error: the single problem on one line, several one per line.
#[derive(Debug, Clone, PartialEq, Error)]
pub struct InvalidFields(pub Vec<Problem>);

impl std::fmt::Display for InvalidFields {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.0.as_slice() {
            [one] => write!(f, "{one}"),
            many => {
                write!(f, "{} bad fields:", many.len())?;
                many.iter().try_for_each(|p| write!(f, "\n  {p}"))
            }
        }
    }
}

impl InvalidFields {
    /// The bad fields' names, in the order found.
    pub fn fields(&self) -> Vec<String> {
        self.0.iter().map(|p| p.field.clone()).collect()
    }
}

/// Collects every bad field of one input.
#[derive(Debug, Default)]
pub struct Problems {
    list: Vec<Problem>,
}

impl Problems {
    pub fn new() -> Self {
        Problems::default()
    }

    pub fn push(&mut self, field: impl Into<String>, value: impl Into<String>, allowed: impl Into<String>) {
        let value = quoted(value.into());
        self.list.push(Problem { field: field.into(), value, allowed: allowed.into() });
    }

    /// `value` must be finite and inside `ok`; `allowed` says so in words.
    pub fn check(&mut self, field: &str, value: f64, ok: impl FnOnce(f64) -> bool, allowed: &str) {
        self.require(field, value, value.is_finite() && ok(value), allowed);
    }

    /// `value` must be finite and `ok` (a condition that may involve other fields) must hold.
    pub fn require(&mut self, field: &str, value: f64, ok: bool, allowed: &str) {
        if !(value.is_finite() && ok) {
            self.push(field, value.to_string(), allowed);
        }
    }

    pub fn finite(&mut self, field: &str, value: f64) {
        self.require(field, value, true, "a finite number");
    }

    pub fn positive(&mut self, field: &str, value: f64) {
        self.check(field, value, |v| v > 0.0, "a finite number > 0");
    }

    pub fn non_negative(&mut self, field: &str, value: f64) {
        self.check(field, value, |v| v >= 0.0, "a finite number >= 0");
    }

    /// A probability: finite and in [0, 1].
    pub fn probability(&mut self, field: &str, value: f64) {
        self.check(field, value, |v| (0.0..=1.0).contains(&v), "a probability in [0, 1]");
    }

    /// Adds the problems an inner validator found.
    pub fn absorb(&mut self, found: Result<(), InvalidFields>) {
        if let Err(InvalidFields(list)) = found {
            self.list.extend(list);
        }
    }

    pub fn is_empty(&self) -> bool {
        self.list.is_empty()
    }

    /// Ok when nothing was found, else every problem.
    pub fn finish(self) -> Result<(), InvalidFields> {
        if self.list.is_empty() {
            Ok(())
        } else {
            Err(InvalidFields(self.list))
        }
    }
}

/// A settings type that checks its own fields into a [`Problems`]; `prefix` is where it sits in
/// its file (`"filters.auv."`), so each problem names the full field.
pub trait CheckFields {
    fn check_fields(&self, prefix: &str, p: &mut Problems);

    /// Every bad field, or Ok.
    fn validate(&self, prefix: &str) -> Result<(), InvalidFields> {
        let mut p = Problems::new();
        self.check_fields(prefix, &mut p);
        p.finish()
    }
}

/// `message` with every line quoted as [`quoted`] quotes a value: a parser's error that echoes
/// a megabyte-long line of the input stays readable.
pub fn shortened(message: &str) -> String {
    message.lines().map(|l| quoted(l.to_string())).collect::<Vec<_>>().join("\n")
}

/// The most characters of an offending value a message quotes.
pub const MAX_QUOTED_CHARS: usize = 200;

/// `value` as a message quotes it: whole when short, else its first [`MAX_QUOTED_CHARS`]
/// characters and how many more there were (a megabyte-long value must not fill the terminal).
pub fn quoted(value: String) -> String {
    match value.char_indices().nth(MAX_QUOTED_CHARS) {
        None => value,
        Some((cut, _)) => {
            let more = value[cut..].chars().count();
            format!("{}… ({more} more characters)", &value[..cut])
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_bad_field_is_reported_once_with_its_value_and_rule() {
        let mut p = Problems::new();
        p.positive("a", f64::NAN);
        p.non_negative("b", -1.0);
        p.probability("c", 1.5);
        p.positive("ok", 2.0);
        p.require("d", 3.0, false, "below e");
        p.finite("e", f64::INFINITY);
        let e = p.finish().unwrap_err();
        let fields: Vec<&str> = e.0.iter().map(|p| p.field.as_str()).collect();
        assert_eq!(fields, ["a", "b", "c", "d", "e"]);
        let text = e.to_string();
        assert!(text.starts_with("5 bad fields:\n  field a = NaN: allowed a finite number > 0\n"), "{text}");
        assert!(text.contains("field d = 3: allowed below e"), "{text}");
    }

    #[test]
    fn one_problem_is_one_line_and_none_is_ok() {
        assert!(Problems::new().finish().is_ok());
        let mut p = Problems::new();
        p.non_negative("q[2]", -1.0);
        assert_eq!(p.finish().unwrap_err().to_string(), "field q[2] = -1: allowed a finite number >= 0");
    }
}
