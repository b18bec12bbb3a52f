//! Pseudo-random values of any schema type, from a seed: for round-trip tests, interoperability
//! tests against the official library, and benchmarks. Variable arrays get lengths in
//! `0..=max_len`; floats are finite (so values compare equal to themselves); strings mix ASCII
//! and multi-byte UTF-8.

use crate::schema::{Dim, Primitive, Schema, Ty};
use crate::value::{Record, Value};

/// A small deterministic generator (splitmix64).
#[derive(Debug, Clone)]
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in `0..=n`.
    pub fn upto(&mut self, n: u64) -> u64 {
        self.next_u64() % (n + 1)
    }
}

/// A random record of the struct at `index`, variable arrays at most `max_len` long.
pub fn record(schema: &Schema, index: usize, rng: &mut Rng, max_len: u64) -> Record {
    record_at(schema, index, rng, max_len, 0)
}

fn record_at(schema: &Schema, index: usize, rng: &mut Rng, max_len: u64, depth: usize) -> Record {
    let def = schema.at(index);
    let mut fields: Vec<(String, Value)> = Vec::with_capacity(def.members.len());
    // Members that size arrays are drawn small and non-negative.
    let sizes: Vec<bool> = (0..def.members.len())
        .map(|i| {
            def.members.iter().any(|m| m.dims.iter().any(|d| matches!(d, Dim::Var { member, .. } if *member == i)))
        })
        .collect();
    for (i, m) in def.members.iter().enumerate() {
        let value = if sizes[i] {
            let n = if depth > 3 { 0 } else { rng.upto(max_len) as i64 };
            match m.ty {
                Ty::Primitive(Primitive::Int8) => Value::Int8(n as i8),
                Ty::Primitive(Primitive::Int16) => Value::Int16(n as i16),
                Ty::Primitive(Primitive::Int32) => Value::Int32(n as i32),
                _ => Value::Int64(n),
            }
        } else {
            let dims: Vec<usize> = m
                .dims
                .iter()
                .map(|d| match d {
                    Dim::Const { size, .. } => *size,
                    Dim::Var { member, .. } => fields[*member].1.as_i64().expect("an integer") as usize,
                })
                .collect();
            array(schema, m.ty, &dims, rng, max_len, depth)
        };
        fields.push((m.name.clone(), value));
    }
    Record { type_name: def.name.clone(), fields }
}

fn array(schema: &Schema, ty: Ty, dims: &[usize], rng: &mut Rng, max_len: u64, depth: usize) -> Value {
    match dims.split_first() {
        None => scalar(schema, ty, rng, max_len, depth),
        Some((&n, [])) if ty == Ty::Primitive(Primitive::Byte) => {
            Value::Bytes((0..n).map(|_| rng.next_u64() as u8).collect())
        }
        Some((&n, inner)) => Value::Array((0..n).map(|_| array(schema, ty, inner, rng, max_len, depth)).collect()),
    }
}

const PIECES: &[&str] = &["", "a", "CNA", "Ωmega", "ünïcode", "波", " ", "range_42", "\u{1F30A}"];

fn finite_f64(rng: &mut Rng) -> f64 {
    match rng.upto(5) {
        0 => 0.0,
        1 => -0.0,
        2 => f64::MAX,
        _ => loop {
            let v = f64::from_bits(rng.next_u64());
            if v.is_finite() {
                break v;
            }
        },
    }
}

fn finite_f32(rng: &mut Rng) -> f32 {
    match rng.upto(5) {
        0 => 0.0,
        1 => f32::MIN_POSITIVE,
        2 => f32::MIN,
        _ => loop {
            let v = f32::from_bits(rng.next_u64() as u32);
            if v.is_finite() {
                break v;
            }
        },
    }
}

fn scalar(schema: &Schema, ty: Ty, rng: &mut Rng, max_len: u64, depth: usize) -> Value {
    let p = match ty {
        Ty::Struct(index) => return Value::Struct(record_at(schema, index, rng, max_len, depth + 1)),
        Ty::Primitive(p) => p,
    };
    let bits = rng.next_u64();
    match p {
        Primitive::Int8 => Value::Int8(bits as i8),
        Primitive::Int16 => Value::Int16(bits as i16),
        Primitive::Int32 => Value::Int32(bits as i32),
        Primitive::Int64 => Value::Int64(bits as i64),
        Primitive::Float => Value::Float(finite_f32(rng)),
        Primitive::Double => Value::Double(finite_f64(rng)),
        Primitive::Boolean => Value::Boolean(bits & 1 == 1),
        Primitive::Byte => Value::Byte(bits as u8),
        Primitive::String => {
            let n = rng.upto(4);
            Value::String((0..n).map(|_| PIECES[rng.upto(PIECES.len() as u64 - 1) as usize]).collect())
        }
    }
}
