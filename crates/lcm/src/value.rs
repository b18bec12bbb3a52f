//! The dynamic value of an LCM message: what the codec encodes from and decodes into, shaped by a
//! [`crate::schema::StructDef`].

/// One value of an LCM type.
///
/// An array is an [`Value::Array`] per dimension, outermost first; the innermost dimension of a
/// `byte` array is a [`Value::Bytes`] (so a `byte data[n]` is one `Bytes`, a `byte f[2][n]` an
/// `Array` of two `Bytes`).
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    Int8(i8),
    Int16(i16),
    Int32(i32),
    Int64(i64),
    Float(f32),
    Double(f64),
    Boolean(bool),
    Byte(u8),
    String(String),
    Bytes(Vec<u8>),
    Array(Vec<Value>),
    Struct(Record),
}

/// A struct's value: its type's package-qualified name and its fields in declaration order.
#[derive(Debug, Clone, PartialEq)]
pub struct Record {
    pub type_name: String,
    pub fields: Vec<(String, Value)>,
}

impl Record {
    /// An empty record of a type, to be filled with [`Record::with`].
    pub fn new(type_name: impl Into<String>) -> Self {
        Self { type_name: type_name.into(), fields: Vec::new() }
    }

    /// The record with one more field.
    #[must_use]
    pub fn with(mut self, name: impl Into<String>, value: Value) -> Self {
        self.fields.push((name.into(), value));
        self
    }

    /// A field by name.
    pub fn get(&self, name: &str) -> Option<&Value> {
        self.fields.iter().find(|(n, _)| n == name).map(|(_, v)| v)
    }

    /// A field by name, looked for at `hint` first (the encoder's usual case: fields in order).
    pub(crate) fn get_at(&self, hint: usize, name: &str) -> Option<&Value> {
        match self.fields.get(hint) {
            Some((n, v)) if n == name => Some(v),
            _ => self.get(name),
        }
    }
}

impl Value {
    /// The value as an integer, when it is one of the integer kinds (an array dimension).
    pub fn as_i64(&self) -> Option<i64> {
        match *self {
            Self::Int8(v) => Some(v.into()),
            Self::Int16(v) => Some(v.into()),
            Self::Int32(v) => Some(v.into()),
            Self::Int64(v) => Some(v),
            _ => None,
        }
    }

    /// The value as a double, when it is a `double` or a `float`.
    pub fn as_f64(&self) -> Option<f64> {
        match *self {
            Self::Double(v) => Some(v),
            Self::Float(v) => Some(v.into()),
            _ => None,
        }
    }

    /// The record, when the value is a struct.
    pub fn as_record(&self) -> Option<&Record> {
        match self {
            Self::Struct(r) => Some(r),
            _ => None,
        }
    }

    /// A short name of the value's kind, for error messages.
    pub fn kind(&self) -> &'static str {
        match self {
            Self::Int8(_) => "int8_t",
            Self::Int16(_) => "int16_t",
            Self::Int32(_) => "int32_t",
            Self::Int64(_) => "int64_t",
            Self::Float(_) => "float",
            Self::Double(_) => "double",
            Self::Boolean(_) => "boolean",
            Self::Byte(_) => "byte",
            Self::String(_) => "string",
            Self::Bytes(_) => "bytes",
            Self::Array(_) => "array",
            Self::Struct(_) => "struct",
        }
    }
}
