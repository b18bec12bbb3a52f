//! LCM's binary encoding: a [`Record`] to bytes and back, driven by a [`Schema`].
//!
//! The rules, restated from the LCM type specification (`docs/content/lcm-type-ref.md`) and the
//! code lcm-gen emits:
//! - a top-level message starts with its type's 64-bit fingerprint, big-endian; a nested struct
//!   is encoded in place, without a fingerprint;
//! - members follow in declaration order, each primitive big-endian: `int8_t`/`byte`/`boolean`
//!   one byte (a boolean 0 or 1), `int16_t` two, `int32_t`/`float` four, `int64_t`/`double`
//!   eight (IEEE 754);
//! - a string is an `int32_t` byte count that includes a terminating NUL, the UTF-8 bytes, then
//!   the NUL;
//! - an array is its elements in row-major order with no length prefix: a constant dimension's
//!   size is in the type, a variable dimension's is the value of an earlier integer member.
//!
//! Decoding trusts nothing: every length is checked against the bytes left before anything is
//! allocated for it, and a wrong fingerprint, a short buffer, a negative or oversized length, a
//! string without its NUL or not UTF-8, a boolean other than 0/1 and bytes left over are refused.

use crate::error::CodecError;
use crate::schema::{Dim, Primitive, Schema, Ty};
use crate::value::{Record, Value};

/// Nested structs deeper than this are refused (a recursive type could otherwise exhaust the stack).
pub const MAX_DEPTH: usize = 64;

/// Encodes a top-level message: the fingerprint of `record`'s type, then its fields.
pub fn encode(schema: &Schema, record: &Record) -> Result<Vec<u8>, CodecError> {
    let mut out = Vec::new();
    encode_into(schema, record, &mut out)?;
    Ok(out)
}

/// As [`encode`], appending to `out` (cleared first).
pub fn encode_into(schema: &Schema, record: &Record, out: &mut Vec<u8>) -> Result<(), CodecError> {
    out.clear();
    let index = schema.index(&record.type_name)?;
    out.extend_from_slice(&schema.at(index).fingerprint.to_be_bytes());
    Encoder { schema, out }.structure(index, record, 0)
}

/// Decodes a top-level message of the named type, checking its fingerprint and that nothing is
/// left over.
pub fn decode(schema: &Schema, type_name: &str, bytes: &[u8]) -> Result<Record, CodecError> {
    let index = schema.index(type_name)?;
    let mut d = Decoder { schema, buf: bytes, pos: 0 };
    let found = u64::from_be_bytes(d.take(8, "fingerprint")?.try_into().expect("8 bytes"));
    let expected = schema.at(index).fingerprint;
    if found != expected {
        return Err(CodecError::Fingerprint { expected, found });
    }
    let record = d.structure(index, 0)?;
    match bytes.len() - d.pos {
        0 => Ok(record),
        n => Err(CodecError::TrailingBytes(n)),
    }
}

/// The fingerprint at the start of a message, if it has eight bytes.
pub fn peek_fingerprint(bytes: &[u8]) -> Option<u64> {
    bytes.get(..8).map(|b| u64::from_be_bytes(b.try_into().expect("8 bytes")))
}

fn mismatch(structure: &str, member: &str, reason: impl Into<String>) -> CodecError {
    CodecError::Mismatch { field: format!("{structure}.{member}"), reason: reason.into() }
}

struct Encoder<'a> {
    schema: &'a Schema,
    out: &'a mut Vec<u8>,
}

impl Encoder<'_> {
    fn structure(&mut self, index: usize, record: &Record, depth: usize) -> Result<(), CodecError> {
        let def = self.schema.at(index);
        if depth > MAX_DEPTH {
            return Err(mismatch(&def.name, "", "nested too deeply"));
        }
        if record.type_name != def.name {
            return Err(mismatch(&def.name, "", format!("a record of type {}", record.type_name)));
        }
        let mut dims = Vec::new();
        for (i, m) in def.members.iter().enumerate() {
            let value = record.get_at(i, &m.name).ok_or_else(|| mismatch(&def.name, &m.name, "missing"))?;
            dims.clear();
            for d in &m.dims {
                dims.push(match d {
                    Dim::Const { size, .. } => *size,
                    Dim::Var { name, .. } => {
                        let n = record
                            .get(name)
                            .and_then(Value::as_i64)
                            .ok_or_else(|| mismatch(&def.name, name, "missing or not an integer"))?;
                        usize::try_from(n).map_err(|_| mismatch(&def.name, name, "a negative array length"))?
                    }
                });
            }
            self.array(m.ty, &dims, value, &def.name, &m.name, depth)?;
        }
        Ok(())
    }

    fn array(
        &mut self,
        ty: Ty,
        dims: &[usize],
        value: &Value,
        structure: &str,
        member: &str,
        depth: usize,
    ) -> Result<(), CodecError> {
        let Some((&n, inner)) = dims.split_first() else {
            return self.scalar(ty, value, structure, member, depth);
        };
        match value {
            Value::Bytes(bytes) if inner.is_empty() && ty == Ty::Primitive(Primitive::Byte) => {
                if bytes.len() != n {
                    return Err(mismatch(structure, member, format!("{} bytes where the length is {n}", bytes.len())));
                }
                self.out.extend_from_slice(bytes);
                Ok(())
            }
            Value::Array(items) => {
                if items.len() != n {
                    return Err(mismatch(
                        structure,
                        member,
                        format!("{} elements where the length is {n}", items.len()),
                    ));
                }
                items.iter().try_for_each(|item| self.array(ty, inner, item, structure, member, depth))
            }
            other => Err(mismatch(structure, member, format!("a {} where an array belongs", other.kind()))),
        }
    }

    fn scalar(&mut self, ty: Ty, value: &Value, structure: &str, member: &str, depth: usize) -> Result<(), CodecError> {
        let out = &mut *self.out;
        match (ty, value) {
            (Ty::Primitive(Primitive::Int8), Value::Int8(v)) => out.extend_from_slice(&v.to_be_bytes()),
            (Ty::Primitive(Primitive::Int16), Value::Int16(v)) => out.extend_from_slice(&v.to_be_bytes()),
            (Ty::Primitive(Primitive::Int32), Value::Int32(v)) => out.extend_from_slice(&v.to_be_bytes()),
            (Ty::Primitive(Primitive::Int64), Value::Int64(v)) => out.extend_from_slice(&v.to_be_bytes()),
            (Ty::Primitive(Primitive::Float), Value::Float(v)) => out.extend_from_slice(&v.to_be_bytes()),
            (Ty::Primitive(Primitive::Double), Value::Double(v)) => out.extend_from_slice(&v.to_be_bytes()),
            (Ty::Primitive(Primitive::Boolean), Value::Boolean(v)) => out.push(u8::from(*v)),
            (Ty::Primitive(Primitive::Byte), Value::Byte(v)) => out.push(*v),
            (Ty::Primitive(Primitive::String), Value::String(s)) => {
                let len = i32::try_from(s.len() + 1).map_err(|_| mismatch(structure, member, "a string too long"))?;
                out.extend_from_slice(&len.to_be_bytes());
                out.extend_from_slice(s.as_bytes());
                out.push(0);
            }
            (Ty::Struct(index), Value::Struct(record)) => return self.structure(index, record, depth + 1),
            (ty, other) => {
                let want = match ty {
                    Ty::Primitive(p) => p.name(),
                    Ty::Struct(_) => "struct",
                };
                return Err(mismatch(structure, member, format!("a {} where a {want} belongs", other.kind())));
            }
        }
        Ok(())
    }
}

struct Decoder<'a> {
    schema: &'a Schema,
    buf: &'a [u8],
    pos: usize,
}

impl<'a> Decoder<'a> {
    fn remaining(&self) -> usize {
        self.buf.len() - self.pos
    }

    fn take(&mut self, n: usize, field: &str) -> Result<&'a [u8], CodecError> {
        if n > self.remaining() {
            return Err(CodecError::Truncated { field: field.to_string(), needed: n, remaining: self.remaining() });
        }
        let s = &self.buf[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }

    fn array_of<const N: usize>(&mut self, field: &str) -> Result<[u8; N], CodecError> {
        Ok(self.take(N, field)?.try_into().expect("N bytes"))
    }

    fn structure(&mut self, index: usize, depth: usize) -> Result<Record, CodecError> {
        let def = self.schema.at(index);
        if depth > MAX_DEPTH {
            return Err(mismatch(&def.name, "", "nested too deeply"));
        }
        let mut fields: Vec<(String, Value)> = Vec::with_capacity(def.members.len());
        let mut dims = Vec::new();
        for m in &def.members {
            dims.clear();
            let mut total: u64 = 1;
            for d in &m.dims {
                let n = match d {
                    Dim::Const { size, .. } => *size as u64,
                    Dim::Var { member, .. } => {
                        let n = fields[*member].1.as_i64().expect("a dimension member is an integer");
                        if n < 0 {
                            return Err(CodecError::NegativeLength {
                                field: format!("{}.{}", def.name, m.name),
                                length: n,
                            });
                        }
                        n as u64
                    }
                };
                total = total.saturating_mul(n);
                dims.push(n as usize);
            }
            if !m.dims.is_empty() {
                let one = match m.ty {
                    Ty::Primitive(p) => p.min_size(),
                    Ty::Struct(child) => self.schema.at(child).min_size,
                }
                .max(1) as u64;
                let needed = total.saturating_mul(one);
                if needed > self.remaining() as u64 {
                    return Err(CodecError::OversizedLength {
                        field: format!("{}.{}", def.name, m.name),
                        length: total,
                        needed,
                        remaining: self.remaining(),
                    });
                }
            }
            let value = self.array(m.ty, &dims, &def.name, &m.name, depth)?;
            fields.push((m.name.clone(), value));
        }
        Ok(Record { type_name: def.name.clone(), fields })
    }

    /// Decodes an array whose every dimension was already bounded by the bytes left.
    fn array(
        &mut self,
        ty: Ty,
        dims: &[usize],
        structure: &str,
        member: &str,
        depth: usize,
    ) -> Result<Value, CodecError> {
        let Some((&n, inner)) = dims.split_first() else {
            return self.scalar(ty, structure, member, depth);
        };
        if inner.is_empty() && ty == Ty::Primitive(Primitive::Byte) {
            return Ok(Value::Bytes(self.take(n, member)?.to_vec()));
        }
        let mut items = Vec::with_capacity(n);
        for _ in 0..n {
            items.push(self.array(ty, inner, structure, member, depth)?);
        }
        Ok(Value::Array(items))
    }

    fn scalar(&mut self, ty: Ty, structure: &str, member: &str, depth: usize) -> Result<Value, CodecError> {
        let p = match ty {
            Ty::Struct(index) => return Ok(Value::Struct(self.structure(index, depth + 1)?)),
            Ty::Primitive(p) => p,
        };
        Ok(match p {
            Primitive::Int8 => Value::Int8(i8::from_be_bytes(self.array_of(member)?)),
            Primitive::Int16 => Value::Int16(i16::from_be_bytes(self.array_of(member)?)),
            Primitive::Int32 => Value::Int32(i32::from_be_bytes(self.array_of(member)?)),
            Primitive::Int64 => Value::Int64(i64::from_be_bytes(self.array_of(member)?)),
            Primitive::Float => Value::Float(f32::from_be_bytes(self.array_of(member)?)),
            Primitive::Double => Value::Double(f64::from_be_bytes(self.array_of(member)?)),
            Primitive::Byte => Value::Byte(self.array_of::<1>(member)?[0]),
            Primitive::Boolean => match self.array_of::<1>(member)?[0] {
                0 => Value::Boolean(false),
                1 => Value::Boolean(true),
                byte => return Err(CodecError::InvalidBoolean { field: format!("{structure}.{member}"), byte }),
            },
            Primitive::String => {
                let field = || format!("{structure}.{member}");
                let len = i32::from_be_bytes(self.array_of(member)?);
                if len <= 0 {
                    return Err(CodecError::BadStringLength { field: field(), length: len.into() });
                }
                let bytes = self.take(len as usize, member)?;
                let (text, nul) = bytes.split_at(bytes.len() - 1);
                if nul != [0] {
                    return Err(CodecError::StringWithoutNul { field: field() });
                }
                let text = std::str::from_utf8(text).map_err(|_| CodecError::InvalidUtf8 { field: field() })?;
                Value::String(text.to_string())
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sample::{self, Rng};

    fn estimate(auv: i16) -> Record {
        Record::new("coopnav.auv_estimate_t")
            .with("utime", Value::Int64(1_700_000_000_000_000))
            .with("auv", Value::Int16(auv))
            .with("x", Value::Double(12.5))
            .with("y", Value::Double(-3.25))
            .with(
                "cov",
                Value::Array(vec![
                    Value::Array(vec![Value::Double(4.0), Value::Double(0.5)]),
                    Value::Array(vec![Value::Double(0.5), Value::Double(9.0)]),
                ]),
            )
            .with("valid", Value::Boolean(true))
    }

    fn team() -> Record {
        Record::new("coopnav.team_estimate_t")
            .with("utime", Value::Int64(-1))
            .with("n", Value::Int8(2))
            .with("auvs", Value::Array(vec![Value::Struct(estimate(1)), Value::Struct(estimate(2))]))
            .with("names", Value::Array(vec![Value::String("a".into()), Value::String("Ωb".into())]))
            .with("flags", Value::Array(vec![Value::Bytes(vec![1, 2]), Value::Bytes(vec![3, 4])]))
    }

    #[test]
    fn layout_of_a_nested_message() {
        let schema = Schema::coopnav();
        let bytes = encode(&schema, &team()).unwrap();
        let fp = schema.get("coopnav.team_estimate_t").unwrap().fingerprint;
        assert_eq!(bytes[..8], fp.to_be_bytes());
        assert_eq!(bytes[8..16], (-1i64).to_be_bytes());
        assert_eq!(bytes[16], 2);
        // The nested estimates follow without a fingerprint: utime first.
        assert_eq!(bytes[17..25], 1_700_000_000_000_000i64.to_be_bytes());
        let estimate_len = 8 + 2 + 8 + 8 + 4 * 8 + 1;
        let names = 17 + 2 * estimate_len;
        assert_eq!(bytes[names..names + 6], [0, 0, 0, 2, b'a', 0]);
        assert_eq!(bytes[names + 6..names + 10], [0, 0, 0, 4]);
        assert_eq!(bytes[bytes.len() - 4..], [1, 2, 3, 4]);
        assert_eq!(decode(&schema, "coopnav.team_estimate_t", &bytes).unwrap(), team());
    }

    #[test]
    fn mismatched_values_are_refused_on_encode() {
        let schema = Schema::coopnav();
        let mut short = team();
        short.fields[4].1 = Value::Array(vec![Value::Bytes(vec![1, 2]), Value::Bytes(vec![3])]);
        assert!(matches!(encode(&schema, &short), Err(CodecError::Mismatch { .. })));
        let mut wrong = team();
        wrong.fields[0].1 = Value::Int32(0);
        assert!(matches!(encode(&schema, &wrong), Err(CodecError::Mismatch { .. })));
        let mut missing = team();
        missing.fields.pop();
        assert!(matches!(encode(&schema, &missing), Err(CodecError::Mismatch { .. })));
        assert!(matches!(encode(&schema, &Record::new("coopnav.nope")), Err(CodecError::Schema(_))));
    }

    #[test]
    fn malformed_messages_are_refused() {
        let schema = Schema::coopnav();
        let t = "coopnav.team_estimate_t";
        let good = encode(&schema, &team()).unwrap();
        let mut bad = good.clone();
        bad[0] ^= 1;
        assert!(matches!(decode(&schema, t, &bad), Err(CodecError::Fingerprint { .. })));
        for cut in 0..good.len() {
            assert!(decode(&schema, t, &good[..cut]).is_err(), "a prefix of {cut} bytes decoded");
        }
        let mut long = good.clone();
        long.push(0);
        assert_eq!(decode(&schema, t, &long), Err(CodecError::TrailingBytes(1)));
        let mut negative = good.clone();
        negative[16] = 0xff;
        assert!(matches!(decode(&schema, t, &negative), Err(CodecError::NegativeLength { length: -1, .. })));
        let mut oversized = good.clone();
        oversized[16] = 127;
        assert!(matches!(decode(&schema, t, &oversized), Err(CodecError::OversizedLength { length: 127, .. })));
        let names = 17 + 2 * 59;
        let mut no_nul = good.clone();
        no_nul[names + 5] = b'x';
        assert!(matches!(decode(&schema, t, &no_nul), Err(CodecError::StringWithoutNul { .. })));
        let mut not_utf8 = good.clone();
        not_utf8[names + 4] = 0xff;
        assert!(matches!(decode(&schema, t, &not_utf8), Err(CodecError::InvalidUtf8 { .. })));
        let mut zero_len = good.clone();
        zero_len[names + 3] = 0;
        assert!(matches!(decode(&schema, t, &zero_len), Err(CodecError::BadStringLength { length: 0, .. })));
        let mut huge_len = good.clone();
        huge_len[names..names + 4].copy_from_slice(&i32::MAX.to_be_bytes());
        assert!(matches!(decode(&schema, t, &huge_len), Err(CodecError::Truncated { .. })));
        let mut bad_bool = good.clone();
        bad_bool[17 + 58] = 2;
        assert!(matches!(decode(&schema, t, &bad_bool), Err(CodecError::InvalidBoolean { byte: 2, .. })));
    }

    #[test]
    fn a_lying_length_allocates_nothing_big() {
        // status_frame_t: utime, src, receive_time, n, data[n]; n = i32::MAX with no data behind.
        let schema = Schema::coopnav();
        let t = "coopnav.status_frame_t";
        let mut bytes = schema.get(t).unwrap().fingerprint.to_be_bytes().to_vec();
        bytes.extend_from_slice(&[0; 8 + 2 + 8]);
        bytes.extend_from_slice(&i32::MAX.to_be_bytes());
        assert!(matches!(decode(&schema, t, &bytes), Err(CodecError::OversizedLength { .. })));
    }

    #[test]
    fn recursive_types_fingerprint_and_decode_within_bounds() {
        // lcm-type-ref's example of mutually recursive types; without the rotation B() == C().
        let src = "struct A { int8_t nb; B b[nb]; int8_t nc; C c[nc]; } \
                   struct B { int8_t na; A a[na]; } struct C { int8_t nb; B b[nb]; }";
        let schema = Schema::from_sources([("abc.lcm", src)]).unwrap();
        let fp = |n| schema.get(n).unwrap().fingerprint;
        assert_ne!(fp("B"), fp("C"));
        // A chain of B -> A -> B ... deeper than MAX_DEPTH is refused, not a stack overflow.
        let mut bytes = fp("B").to_be_bytes().to_vec();
        bytes.extend_from_slice(&[1u8; 400]);
        assert!(decode(&schema, "B", &bytes).is_err());
    }

    proptest::proptest! {
        #[test]
        fn random_values_round_trip(seed in proptest::prelude::any::<u64>(), max_len in 0u64..6) {
            let schema = Schema::coopnav();
            let mut rng = Rng::new(seed);
            for i in 0..schema.structs().len() {
                let v = sample::record(&schema, i, &mut rng, max_len);
                let bytes = encode(&schema, &v).unwrap();
                proptest::prop_assert_eq!(decode(&schema, &v.type_name, &bytes).unwrap(), v);
            }
        }

        #[test]
        fn damaged_bytes_never_panic_and_accepted_bytes_are_canonical(
            seed in proptest::prelude::any::<u64>(),
            flips in proptest::collection::vec((proptest::prelude::any::<usize>(), proptest::prelude::any::<u8>()), 1..4),
        ) {
            let schema = Schema::coopnav();
            let mut rng = Rng::new(seed);
            let index = rng.upto(schema.structs().len() as u64 - 1) as usize;
            let v = sample::record(&schema, index, &mut rng, 4);
            let mut bytes = encode(&schema, &v).unwrap();
            for (at, byte) in flips {
                let at = 8 + at % (bytes.len() - 8).max(1);
                if at < bytes.len() {
                    bytes[at] = byte;
                }
            }
            if let Ok(decoded) = decode(&schema, &v.type_name, &bytes) {
                proptest::prop_assert_eq!(encode(&schema, &decoded).unwrap(), bytes);
            }
        }
    }
}
