//! DCCL-style bit-exact primitives: a bounded integer in [min, max] is sent in
//! ceil(log2(max − min + 2)) bits as value − min + 1, code 0 meaning "not set" (DCCL v2
//! convention; Nams 2014, §5.2). Bits are packed least-significant first into bytes.

use thiserror::Error;

/// A decoding failure: never a panic, always one of these.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum DecodeError {
    #[error("field '{field}': message truncated (needed {needed} more bits, {available} left)")]
    Truncated { field: &'static str, needed: u32, available: usize },
    #[error("field '{field}': code {code} is out of range (value must be in [{min}, {max}])")]
    OutOfRange { field: &'static str, code: u64, min: i64, max: i64 },
    #[error("field '{field}': required value is not set (code 0)")]
    NotSet { field: &'static str },
    #[error("message has {extra} trailing bytes after the last field (oversized)")]
    Oversized { extra: usize },
    #[error("field '{field}': {message}")]
    Invalid { field: &'static str, message: String },
}

/// Encoding failure: a value outside its field's declared bounds.
#[derive(Debug, Clone, PartialEq, Error)]
#[error("field '{field}': value {value} outside [{min}, {max}]")]
pub struct EncodeError {
    pub field: &'static str,
    pub value: i64,
    pub min: i64,
    pub max: i64,
}

/// A bounded-integer field declaration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bounded {
    pub name: &'static str,
    pub min: i64,
    pub max: i64,
}

impl Bounded {
    pub const fn new(name: &'static str, min: i64, max: i64) -> Self {
        Bounded { name, min, max }
    }
    /// ceil(log2(max − min + 2)).
    pub const fn bits(&self) -> u32 {
        let states = (self.max - self.min + 2) as u64;
        64 - (states - 1).leading_zeros()
    }
}

#[derive(Debug, Default, Clone)]
pub struct BitWriter {
    bytes: Vec<u8>,
    bits: usize,
}

impl BitWriter {
    pub fn new() -> Self {
        Self::default()
    }
    pub fn bit_len(&self) -> usize {
        self.bits
    }
    fn push_bits(&mut self, mut code: u64, n: u32) {
        for _ in 0..n {
            if self.bits & 7 == 0 {
                self.bytes.push(0);
            }
            if code & 1 == 1 {
                let last = self.bytes.len() - 1;
                self.bytes[last] |= 1 << (self.bits % 8);
            }
            code >>= 1;
            self.bits += 1;
        }
    }
    /// Writes a set value.
    pub fn put(&mut self, f: Bounded, v: i64) -> Result<(), EncodeError> {
        if v < f.min || v > f.max {
            return Err(EncodeError { field: f.name, value: v, min: f.min, max: f.max });
        }
        self.push_bits((v - f.min + 1) as u64, f.bits());
        Ok(())
    }
    /// Writes a boolean as one bit (DCCL bools carry no "not set" state when required).
    pub fn put_bool(&mut self, b: bool) {
        self.push_bits(b as u64, 1);
    }
    pub fn finish(self) -> Vec<u8> {
        self.bytes
    }
}

pub struct BitReader<'a> {
    bytes: &'a [u8],
    pos: usize,
}

impl<'a> BitReader<'a> {
    pub fn new(bytes: &'a [u8]) -> Self {
        BitReader { bytes, pos: 0 }
    }
    fn remaining(&self) -> usize {
        self.bytes.len() * 8 - self.pos
    }
    fn take(&mut self, field: &'static str, n: u32) -> Result<u64, DecodeError> {
        if (n as usize) > self.remaining() {
            return Err(DecodeError::Truncated { field, needed: n, available: self.remaining() });
        }
        let mut code = 0u64;
        for i in 0..n {
            let bit = (self.bytes[self.pos / 8] >> (self.pos % 8)) & 1;
            code |= (bit as u64) << i;
            self.pos += 1;
        }
        Ok(code)
    }
    /// Reads a required value.
    pub fn get(&mut self, f: Bounded) -> Result<i64, DecodeError> {
        let code = self.take(f.name, f.bits())?;
        if code == 0 {
            return Err(DecodeError::NotSet { field: f.name });
        }
        if code > (f.max - f.min + 1) as u64 {
            return Err(DecodeError::OutOfRange { field: f.name, code, min: f.min, max: f.max });
        }
        Ok(code as i64 - 1 + f.min)
    }
    pub fn get_bool(&mut self, field: &'static str) -> Result<bool, DecodeError> {
        Ok(self.take(field, 1)? == 1)
    }
    /// Checks that only zero padding (< 8 bits) remains.
    pub fn finish(self) -> Result<(), DecodeError> {
        let used = self.pos.div_ceil(8);
        if used < self.bytes.len() {
            return Err(DecodeError::Oversized { extra: self.bytes.len() - used });
        }
        if self.remaining() > 0 && (self.bytes[self.pos / 8] >> (self.pos % 8)) != 0 {
            return Err(DecodeError::Invalid {
                field: "padding",
                message: "non-zero padding bits after the last field".into(),
            });
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dccl_bit_counts() {
        assert_eq!(Bounded::new("cycles_ago", 0, 63).bits(), 7);
        assert_eq!(Bounded::new("mask", 0, 7).bits(), 4);
        assert_eq!(Bounded::new("mask", 0, 255).bits(), 9);
        assert_eq!(Bounded::new("b", 0, 0).bits(), 1);
        assert_eq!(Bounded::new("b", -1, 1).bits(), 2);
    }

    #[test]
    fn exact_bit_layout() {
        let f = Bounded::new("a", 0, 63);
        let g = Bounded::new("b", 0, 7);
        let mut w = BitWriter::new();
        w.put(f, 5).unwrap(); // code 6 = 0b0000110 in 7 bits
        w.put(g, 7).unwrap(); // code 8 = 0b1000 in 4 bits
        assert_eq!(w.bit_len(), 11);
        // bits LSB-first: 0,1,1,0,0,0,0 | 0,0,0,1
        assert_eq!(w.finish(), vec![0b0000_0110, 0b0000_0100]);
        let bytes = [0b0000_0110, 0b0000_0100];
        let mut r = BitReader::new(&bytes);
        assert_eq!(r.get(f), Ok(5));
        assert_eq!(r.get(g), Ok(7));
        r.finish().unwrap();
    }

    #[test]
    fn rejects_bad_codes() {
        let f = Bounded::new("x", 10, 12); // 2 bits... codes 1..3 valid
        assert!(matches!(BitReader::new(&[0]).get(f), Err(DecodeError::NotSet { .. })));
        let g = Bounded::new("y", 0, 4); // 3 bits, codes 1..5 valid
        assert!(matches!(BitReader::new(&[7]).get(g), Err(DecodeError::OutOfRange { code: 7, .. })));
        assert!(matches!(BitReader::new(&[]).get(g), Err(DecodeError::Truncated { .. })));
        let mut w = BitWriter::new();
        assert!(w.put(g, 5).is_err());
        assert!(BitReader::new(&[0, 0]).finish().is_err());
    }
}
