//! The crate's typed errors: one enum per layer (type definitions, codec, transport, log files), so
//! a caller can tell a malformed `.lcm` file from a malformed message or a socket failure.

use thiserror::Error;

/// A `.lcm` type definition that cannot be parsed or does not follow LCM's type rules.
#[derive(Debug, Error, Clone, PartialEq, Eq)]
pub enum SchemaError {
    /// The text does not follow the `.lcm` grammar.
    #[error("{file}:{line}: {message}")]
    Syntax { file: String, line: usize, message: String },
    /// A member's type is neither a primitive nor a struct defined in the schema.
    #[error("struct {structure}: member {member} has unknown type {type_name}")]
    UnknownType { structure: String, member: String, type_name: String },
    /// A variable array dimension that does not name an earlier integer, non-array member.
    #[error("struct {structure}: member {member}: bad array dimension {dimension}: {reason}")]
    BadDimension { structure: String, member: String, dimension: String, reason: &'static str },
    /// The same member or constant name declared twice in one struct.
    #[error("struct {structure}: duplicate name {name}")]
    Duplicate { structure: String, name: String },
    /// The same struct defined twice.
    #[error("struct {0} is defined twice")]
    DuplicateStruct(String),
    /// A type name asked for that the schema does not define.
    #[error("no struct {0} in the schema")]
    NoSuchStruct(String),
}

/// A message that cannot be encoded from, or decoded into, a value of its type.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum CodecError {
    /// The message's first eight bytes are not the type's fingerprint.
    #[error("fingerprint mismatch: expected {expected:#018x}, found {found:#018x}")]
    Fingerprint { expected: u64, found: u64 },
    /// The buffer ends before the field being decoded.
    #[error("truncated: {field} needs {needed} bytes, {remaining} remain")]
    Truncated { field: String, needed: usize, remaining: usize },
    /// An array length read from the message is negative.
    #[error("negative array length {length} for {field}")]
    NegativeLength { field: String, length: i64 },
    /// An array length read from the message that the remaining bytes cannot hold.
    #[error("array length {length} for {field} needs at least {needed} bytes, {remaining} remain")]
    OversizedLength { field: String, length: u64, needed: u64, remaining: usize },
    /// A string's length word is zero or negative, or exceeds the remaining bytes.
    #[error("bad string length {length} for {field}")]
    BadStringLength { field: String, length: i64 },
    /// A string whose last byte is not the terminating NUL.
    #[error("string {field} is not NUL-terminated")]
    StringWithoutNul { field: String },
    /// A string whose bytes are not UTF-8.
    #[error("string {field} is not UTF-8")]
    InvalidUtf8 { field: String },
    /// A boolean byte other than 0 or 1.
    #[error("boolean {field} has byte {byte}, not 0 or 1")]
    InvalidBoolean { field: String, byte: u8 },
    /// Bytes left over after the message's last field.
    #[error("{0} bytes left after the message")]
    TrailingBytes(usize),
    /// A value whose shape does not match its type (wrong kind, missing field, wrong length).
    #[error("value does not match the type at {field}: {reason}")]
    Mismatch { field: String, reason: String },
    /// The type asked for is not in the schema.
    #[error(transparent)]
    Schema(#[from] SchemaError),
}

/// A failure of the UDP multicast transport.
#[derive(Debug, Error)]
pub enum TransportError {
    /// The provider URL cannot be parsed or names an unsupported provider.
    #[error("bad LCM URL {url}: {reason}")]
    BadUrl { url: String, reason: String },
    /// A channel name longer than LCM's limit or containing a NUL.
    #[error("bad channel name {0:?}")]
    BadChannel(String),
    /// A subscription pattern that is not a regular expression.
    #[error("bad channel pattern {pattern:?}: {reason}")]
    BadPattern { pattern: String, reason: String },
    /// A message too large to publish (more than 65535 fragments or over the size limit).
    #[error("message of {0} bytes is too large")]
    TooLarge(usize),
    /// The operating system refused a socket operation.
    #[error("socket: {0}")]
    Io(#[from] std::io::Error),
}

/// A failure reading or writing an LCM log file.
#[derive(Debug, Error)]
pub enum LogError {
    /// The file ends inside an event.
    #[error("log truncated inside event at byte {offset}")]
    Truncated { offset: u64 },
    /// A channel name that is not UTF-8.
    #[error("channel of event at byte {offset} is not UTF-8")]
    BadChannel { offset: u64 },
    /// A channel or data too long for the format or the reader's bounds.
    #[error("event too large: channel {channel_len} bytes, data {data_len} bytes")]
    TooLarge { channel_len: usize, data_len: usize },
    /// The file cannot be read or written.
    #[error("log file: {0}")]
    Io(#[from] std::io::Error),
}
