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
