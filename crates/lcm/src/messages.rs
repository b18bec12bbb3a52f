//! Typed Rust views of coopnav's LCM messages, for the live processes: each converts to and from
//! the dynamic [`Record`] the codec checks against the `.lcm` files, which stay the single source
//! of truth (a field renamed or retyped there makes the conversion fail, in the tests).
//!
//! Array lengths (`n`, `n_options`, ...) are not stored: they are the vectors' lengths, and a
//! vector too long for its length field is refused when encoded.

use crate::codec;
use crate::error::CodecError;
use crate::schema::Schema;
use crate::value::{Record, Value};

/// A message type with a typed Rust view.
pub trait Message: Sized {
    /// The package-qualified LCM type name.
    const TYPE_NAME: &'static str;

    /// The dynamic record of this message.
    fn to_record(&self) -> Record;

    /// The message from a record of its type.
    fn from_record(record: &Record) -> Result<Self, CodecError>;

    /// Encodes the message (fingerprint first).
    fn encode(&self, schema: &Schema) -> Result<Vec<u8>, CodecError> {
        codec::encode(schema, &self.to_record())
    }

    /// Decodes a message of this type.
    fn decode(schema: &Schema, bytes: &[u8]) -> Result<Self, CodecError> {
        Self::from_record(&codec::decode(schema, Self::TYPE_NAME, bytes)?)
    }
}

fn field<'a>(r: &'a Record, name: &str) -> Result<&'a Value, CodecError> {
    r.get(name)
        .ok_or_else(|| CodecError::Mismatch { field: format!("{}.{name}", r.type_name), reason: "missing".into() })
}

fn wrong(r: &Record, name: &str, v: &Value) -> CodecError {
    CodecError::Mismatch { field: format!("{}.{name}", r.type_name), reason: format!("a {}", v.kind()) }
}

macro_rules! getter {
    ($fn:ident, $variant:ident, $t:ty) => {
        fn $fn(r: &Record, name: &str) -> Result<$t, CodecError> {
            match field(r, name)? {
                Value::$variant(v) => Ok(v.clone()),
                v => Err(wrong(r, name, v)),
            }
        }
    };
}
getter!(get_i8, Int8, i8);
getter!(get_i16, Int16, i16);
getter!(get_i32, Int32, i32);
getter!(get_i64, Int64, i64);
getter!(get_f32, Float, f32);
getter!(get_f64, Double, f64);
getter!(get_bool, Boolean, bool);
getter!(get_string, String, String);
getter!(get_bytes, Bytes, Vec<u8>);

fn get_array<'a>(r: &'a Record, name: &str) -> Result<&'a [Value], CodecError> {
    match field(r, name)? {
        Value::Array(items) => Ok(items),
        v => Err(wrong(r, name, v)),
    }
}

fn get_record<'a>(r: &'a Record, name: &str) -> Result<&'a Record, CodecError> {
    match field(r, name)? {
        Value::Struct(inner) => Ok(inner),
        v => Err(wrong(r, name, v)),
    }
}

fn each<T>(r: &Record, name: &str, f: impl Fn(&Value) -> Option<T>) -> Result<Vec<T>, CodecError> {
    get_array(r, name)?.iter().map(|v| f(v).ok_or_else(|| wrong(r, name, v))).collect()
}

fn fixed<T: Copy + Default, const N: usize>(
    r: &Record,
    name: &str,
    f: impl Fn(&Value) -> Option<T>,
) -> Result<[T; N], CodecError> {
    let v = each(r, name, f)?;
    let mut out = [T::default(); N];
    if v.len() != N {
        return Err(CodecError::Mismatch { field: format!("{}.{name}", r.type_name), reason: "wrong length".into() });
    }
    out.copy_from_slice(&v);
    Ok(out)
}

fn as_f32(v: &Value) -> Option<f32> {
    match *v {
        Value::Float(x) => Some(x),
        _ => None,
    }
}

fn as_f64(v: &Value) -> Option<f64> {
    match *v {
        Value::Double(x) => Some(x),
        _ => None,
    }
}

fn doubles(v: &[f64]) -> Value {
    Value::Array(v.iter().map(|&x| Value::Double(x)).collect())
}

fn floats(v: &[f32]) -> Value {
    Value::Array(v.iter().map(|&x| Value::Float(x)).collect())
}

/// A length for an `int8_t` size field (-1, refused on encode, when it does not fit).
fn len_i8(n: usize) -> Value {
    Value::Int8(i8::try_from(n).unwrap_or(-1))
}

/// A length for an `int32_t` size field (-1, refused on encode, when it does not fit).
fn len_i32(n: usize) -> Value {
    Value::Int32(i32::try_from(n).unwrap_or(-1))
}

/// `coopnav.position_t`: x east, y north, z down, metres.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Position {
    pub x: f64,
    pub y: f64,
    pub z: f64,
}

impl Message for Position {
    const TYPE_NAME: &'static str = "coopnav.position_t";
    fn to_record(&self) -> Record {
        Record::new(Self::TYPE_NAME)
            .with("x", Value::Double(self.x))
            .with("y", Value::Double(self.y))
            .with("z", Value::Double(self.z))
    }
    fn from_record(r: &Record) -> Result<Self, CodecError> {
        Ok(Self { x: get_f64(r, "x")?, y: get_f64(r, "y")?, z: get_f64(r, "z")? })
    }
}

/// `coopnav.cna_fix_t`: the CNA's own fix and its variance.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct CnaFix {
    pub utime: i64,
    pub x: f64,
    pub y: f64,
    pub depth: f64,
    /// Radians, counter-clockwise from east.
    pub heading: f64,
    /// Horizontal position variance per axis, m².
    pub variance: f64,
    /// One of [`CnaFix::SOURCE_GPS`], [`CnaFix::SOURCE_DEAD_RECKONING`], [`CnaFix::SOURCE_USBL`].
    pub source: i8,
}

impl CnaFix {
    pub const SOURCE_GPS: i8 = 1;
    pub const SOURCE_DEAD_RECKONING: i8 = 2;
    pub const SOURCE_USBL: i8 = 3;
}

impl Message for CnaFix {
    const TYPE_NAME: &'static str = "coopnav.cna_fix_t";
    fn to_record(&self) -> Record {
        Record::new(Self::TYPE_NAME)
            .with("utime", Value::Int64(self.utime))
            .with("x", Value::Double(self.x))
            .with("y", Value::Double(self.y))
            .with("depth", Value::Double(self.depth))
            .with("heading", Value::Double(self.heading))
            .with("variance", Value::Double(self.variance))
            .with("source", Value::Int8(self.source))
    }
    fn from_record(r: &Record) -> Result<Self, CodecError> {
        Ok(Self {
            utime: get_i64(r, "utime")?,
            x: get_f64(r, "x")?,
            y: get_f64(r, "y")?,
            depth: get_f64(r, "depth")?,
            heading: get_f64(r, "heading")?,
            variance: get_f64(r, "variance")?,
            source: get_i8(r, "source")?,
        })
    }
}

/// `coopnav.status_frame_t`: a received status frame (the status codec's bytes).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct StatusFrame {
    pub utime: i64,
    pub src: i16,
    pub receive_time: f64,
    pub data: Vec<u8>,
}

impl Message for StatusFrame {
    const TYPE_NAME: &'static str = "coopnav.status_frame_t";
    fn to_record(&self) -> Record {
        Record::new(Self::TYPE_NAME)
            .with("utime", Value::Int64(self.utime))
            .with("src", Value::Int16(self.src))
            .with("receive_time", Value::Double(self.receive_time))
            .with("n", len_i32(self.data.len()))
            .with("data", Value::Bytes(self.data.clone()))
    }
    fn from_record(r: &Record) -> Result<Self, CodecError> {
        Ok(Self {
            utime: get_i64(r, "utime")?,
            src: get_i16(r, "src")?,
            receive_time: get_f64(r, "receive_time")?,
            data: get_bytes(r, "data")?,
        })
    }
}

/// `coopnav.owtt_range_t`: a received one-way-travel-time broadcast.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct OwttRange {
    pub utime: i64,
    pub src: i8,
    pub transmit_time: f64,
    pub receive_time: f64,
    pub transponder: Position,
    pub travel_time: f64,
}

impl Message for OwttRange {
    const TYPE_NAME: &'static str = "coopnav.owtt_range_t";
    fn to_record(&self) -> Record {
        Record::new(Self::TYPE_NAME)
            .with("utime", Value::Int64(self.utime))
            .with("src", Value::Int8(self.src))
            .with("transmit_time", Value::Double(self.transmit_time))
            .with("receive_time", Value::Double(self.receive_time))
            .with("transponder", Value::Struct(self.transponder.to_record()))
            .with("travel_time", Value::Double(self.travel_time))
    }
    fn from_record(r: &Record) -> Result<Self, CodecError> {
        Ok(Self {
            utime: get_i64(r, "utime")?,
            src: get_i8(r, "src")?,
            transmit_time: get_f64(r, "transmit_time")?,
            receive_time: get_f64(r, "receive_time")?,
            transponder: Position::from_record(get_record(r, "transponder")?)?,
            travel_time: get_f64(r, "travel_time")?,
        })
    }
}

/// `coopnav.cna_command_t`: the CNA's next leg (a waypoint, or hold).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct CnaCommand {
    pub utime: i64,
    pub seq: i64,
    pub has_waypoint: bool,
    /// Radians, counter-clockwise from east.
    pub heading: f64,
    pub waypoint_x: f64,
    pub waypoint_y: f64,
    pub waypoint_depth: f64,
    pub speed: f32,
}

impl Message for CnaCommand {
    const TYPE_NAME: &'static str = "coopnav.cna_command_t";
    fn to_record(&self) -> Record {
        Record::new(Self::TYPE_NAME)
            .with("utime", Value::Int64(self.utime))
            .with("seq", Value::Int64(self.seq))
            .with("has_waypoint", Value::Boolean(self.has_waypoint))
            .with("heading", Value::Double(self.heading))
            .with("waypoint_x", Value::Double(self.waypoint_x))
            .with("waypoint_y", Value::Double(self.waypoint_y))
            .with("waypoint_depth", Value::Double(self.waypoint_depth))
            .with("speed", Value::Float(self.speed))
    }
    fn from_record(r: &Record) -> Result<Self, CodecError> {
        Ok(Self {
            utime: get_i64(r, "utime")?,
            seq: get_i64(r, "seq")?,
            has_waypoint: get_bool(r, "has_waypoint")?,
            heading: get_f64(r, "heading")?,
            waypoint_x: get_f64(r, "waypoint_x")?,
            waypoint_y: get_f64(r, "waypoint_y")?,
            waypoint_depth: get_f64(r, "waypoint_depth")?,
            speed: get_f32(r, "speed")?,
        })
    }
}

/// `coopnav.decision_t`: one decision of the CNA's policy and the planner's tally.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Decision {
    pub utime: i64,
    pub seq: i64,
    pub policy: String,
    /// One of the `OUTCOME_*` constants.
    pub outcome: i8,
    /// Per motion option (as many as `option_pitch`): its heading change, rad.
    pub option_turn: Vec<f64>,
    pub option_pitch: Vec<f64>,
    pub option: i32,
    pub cost: f64,
    pub levels_requested: i32,
    pub levels_searched: i32,
    pub nodes: i64,
    pub elapsed_s: f64,
    pub fix_utime: i64,
    pub n_status: i32,
    pub decisions: i64,
    pub deadline_misses: i64,
    pub failures: i64,
    pub waiting: i64,
    pub min_levels_searched: i32,
    pub mean_levels_searched: f64,
}

impl Decision {
    pub const OUTCOME_PLANNED: i8 = 1;
    pub const OUTCOME_WAITING: i8 = 2;
    pub const OUTCOME_FAILED: i8 = 3;
    pub const OUTCOME_BASELINE: i8 = 4;
}

impl Message for Decision {
    const TYPE_NAME: &'static str = "coopnav.decision_t";
    fn to_record(&self) -> Record {
        Record::new(Self::TYPE_NAME)
            .with("utime", Value::Int64(self.utime))
            .with("seq", Value::Int64(self.seq))
            .with("policy", Value::String(self.policy.clone()))
            .with("outcome", Value::Int8(self.outcome))
            .with("n_options", len_i32(self.option_turn.len()))
            .with("option_turn", doubles(&self.option_turn))
            .with("option_pitch", doubles(&self.option_pitch))
            .with("option", Value::Int32(self.option))
            .with("cost", Value::Double(self.cost))
            .with("levels_requested", Value::Int32(self.levels_requested))
            .with("levels_searched", Value::Int32(self.levels_searched))
            .with("nodes", Value::Int64(self.nodes))
            .with("elapsed_s", Value::Double(self.elapsed_s))
            .with("fix_utime", Value::Int64(self.fix_utime))
            .with("n_status", Value::Int32(self.n_status))
            .with("decisions", Value::Int64(self.decisions))
            .with("deadline_misses", Value::Int64(self.deadline_misses))
            .with("failures", Value::Int64(self.failures))
            .with("waiting", Value::Int64(self.waiting))
            .with("min_levels_searched", Value::Int32(self.min_levels_searched))
            .with("mean_levels_searched", Value::Double(self.mean_levels_searched))
    }
    fn from_record(r: &Record) -> Result<Self, CodecError> {
        Ok(Self {
            utime: get_i64(r, "utime")?,
            seq: get_i64(r, "seq")?,
            policy: get_string(r, "policy")?,
            outcome: get_i8(r, "outcome")?,
            option_turn: each(r, "option_turn", as_f64)?,
            option_pitch: each(r, "option_pitch", as_f64)?,
            option: get_i32(r, "option")?,
            cost: get_f64(r, "cost")?,
            levels_requested: get_i32(r, "levels_requested")?,
            levels_searched: get_i32(r, "levels_searched")?,
            nodes: get_i64(r, "nodes")?,
            elapsed_s: get_f64(r, "elapsed_s")?,
            fix_utime: get_i64(r, "fix_utime")?,
            n_status: get_i32(r, "n_status")?,
            decisions: get_i64(r, "decisions")?,
            deadline_misses: get_i64(r, "deadline_misses")?,
            failures: get_i64(r, "failures")?,
            waiting: get_i64(r, "waiting")?,
            min_levels_searched: get_i32(r, "min_levels_searched")?,
            mean_levels_searched: get_f64(r, "mean_levels_searched")?,
        })
    }
}

/// `coopnav.auv_estimate_t`: an AUV's position estimate.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct AuvEstimate {
    pub utime: i64,
    pub auv: i16,
    pub x: f64,
    pub y: f64,
    pub cov: [[f64; 2]; 2],
    pub valid: bool,
}

impl Message for AuvEstimate {
    const TYPE_NAME: &'static str = "coopnav.auv_estimate_t";
    fn to_record(&self) -> Record {
        Record::new(Self::TYPE_NAME)
            .with("utime", Value::Int64(self.utime))
            .with("auv", Value::Int16(self.auv))
            .with("x", Value::Double(self.x))
            .with("y", Value::Double(self.y))
            .with("cov", Value::Array(self.cov.iter().map(|row| doubles(row)).collect()))
            .with("valid", Value::Boolean(self.valid))
    }
    fn from_record(r: &Record) -> Result<Self, CodecError> {
        let rows = get_array(r, "cov")?;
        let bad = || CodecError::Mismatch { field: format!("{}.cov", r.type_name), reason: "not 2 x 2".into() };
        let mut cov = [[0.0; 2]; 2];
        if rows.len() != 2 {
            return Err(bad());
        }
        for (row, value) in cov.iter_mut().zip(rows) {
            let Value::Array(items) = value else { return Err(bad()) };
            let items: Vec<f64> = items.iter().map(as_f64).collect::<Option<_>>().ok_or_else(bad)?;
            if items.len() != 2 {
                return Err(bad());
            }
            row.copy_from_slice(&items);
        }
        Ok(Self {
            utime: get_i64(r, "utime")?,
            auv: get_i16(r, "auv")?,
            x: get_f64(r, "x")?,
            y: get_f64(r, "y")?,
            cov,
            valid: get_bool(r, "valid")?,
        })
    }
}

/// `coopnav.auv_sensors_t`: an AUV's dead-reckoning sensors for one step.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct AuvSensors {
    pub utime: i64,
    pub auv: i16,
    pub heading: f64,
    pub speed: f32,
    pub depth: f32,
    pub dvl_lock: bool,
    pub dvl_beam_range: [f32; 4],
    /// The samples' times; as many as `sample_velocity`.
    pub sample_utime: Vec<i64>,
    pub sample_velocity: Vec<[f32; 3]>,
}

impl Message for AuvSensors {
    const TYPE_NAME: &'static str = "coopnav.auv_sensors_t";
    fn to_record(&self) -> Record {
        Record::new(Self::TYPE_NAME)
            .with("utime", Value::Int64(self.utime))
            .with("auv", Value::Int16(self.auv))
            .with("heading", Value::Double(self.heading))
            .with("speed", Value::Float(self.speed))
            .with("depth", Value::Float(self.depth))
            .with("dvl_lock", Value::Boolean(self.dvl_lock))
            .with("dvl_beam_range", floats(&self.dvl_beam_range))
            .with("n_samples", len_i8(self.sample_utime.len()))
            .with("sample_utime", Value::Array(self.sample_utime.iter().map(|&t| Value::Int64(t)).collect()))
            .with("sample_velocity", Value::Array(self.sample_velocity.iter().map(|v| floats(v)).collect()))
    }
    fn from_record(r: &Record) -> Result<Self, CodecError> {
        let velocity = get_array(r, "sample_velocity")?
            .iter()
            .map(|row| {
                let rec = Record::new(r.type_name.clone()).with("sample_velocity", row.clone());
                fixed::<f32, 3>(&rec, "sample_velocity", as_f32)
            })
            .collect::<Result<_, _>>()?;
        Ok(Self {
            utime: get_i64(r, "utime")?,
            auv: get_i16(r, "auv")?,
            heading: get_f64(r, "heading")?,
            speed: get_f32(r, "speed")?,
            depth: get_f32(r, "depth")?,
            dvl_lock: get_bool(r, "dvl_lock")?,
            dvl_beam_range: fixed(r, "dvl_beam_range", as_f32)?,
            sample_utime: each(r, "sample_utime", Value::as_i64)?,
            sample_velocity: velocity,
        })
    }
}

/// `coopnav.clock_t`: the world clock's tick.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Clock {
    pub utime: i64,
    pub tick: i64,
    pub dt: f64,
    pub running: bool,
}

impl Message for Clock {
    const TYPE_NAME: &'static str = "coopnav.clock_t";
    fn to_record(&self) -> Record {
        Record::new(Self::TYPE_NAME)
            .with("utime", Value::Int64(self.utime))
            .with("tick", Value::Int64(self.tick))
            .with("dt", Value::Double(self.dt))
            .with("running", Value::Boolean(self.running))
    }
    fn from_record(r: &Record) -> Result<Self, CodecError> {
        Ok(Self {
            utime: get_i64(r, "utime")?,
            tick: get_i64(r, "tick")?,
            dt: get_f64(r, "dt")?,
            running: get_bool(r, "running")?,
        })
    }
}

/// `coopnav.team_estimate_t`: every AUV's estimate at one time.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct TeamEstimate {
    pub utime: i64,
    pub auvs: Vec<AuvEstimate>,
    /// One per AUV.
    pub names: Vec<String>,
    /// Two rows, one byte per AUV each.
    pub flags: [Vec<u8>; 2],
}

impl Message for TeamEstimate {
    const TYPE_NAME: &'static str = "coopnav.team_estimate_t";
    fn to_record(&self) -> Record {
        Record::new(Self::TYPE_NAME)
            .with("utime", Value::Int64(self.utime))
            .with("n", len_i8(self.auvs.len()))
            .with("auvs", Value::Array(self.auvs.iter().map(|a| Value::Struct(a.to_record())).collect()))
            .with("names", Value::Array(self.names.iter().map(|s| Value::String(s.clone())).collect()))
            .with("flags", Value::Array(self.flags.iter().map(|f| Value::Bytes(f.clone())).collect()))
    }
    fn from_record(r: &Record) -> Result<Self, CodecError> {
        let auvs = get_array(r, "auvs")?
            .iter()
            .map(|v| match v {
                Value::Struct(inner) => AuvEstimate::from_record(inner),
                v => Err(wrong(r, "auvs", v)),
            })
            .collect::<Result<_, _>>()?;
        let names = each(r, "names", |v| match v {
            Value::String(s) => Some(s.clone()),
            _ => None,
        })?;
        let rows = each(r, "flags", |v| match v {
            Value::Bytes(b) => Some(b.clone()),
            _ => None,
        })?;
        let flags: [Vec<u8>; 2] = rows.try_into().map_err(|_| CodecError::Mismatch {
            field: format!("{}.flags", r.type_name),
            reason: "not two rows".into(),
        })?;
        Ok(Self { utime: get_i64(r, "utime")?, auvs, names, flags })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sample::{self, Rng};

    /// Every typed view reads a random record of its type and writes it back unchanged.
    fn round_trip<M: Message + PartialEq + std::fmt::Debug>(schema: &Schema) {
        let mut rng = Rng::new(11);
        let index = schema.index(M::TYPE_NAME).unwrap();
        for max_len in 0..6 {
            let record = sample::record(schema, index, &mut rng, max_len);
            let typed = M::from_record(&record).unwrap();
            assert_eq!(typed.to_record(), record, "{}", M::TYPE_NAME);
            let bytes = typed.encode(schema).unwrap();
            assert_eq!(M::decode(schema, &bytes).unwrap(), typed);
        }
    }

    #[test]
    fn typed_views_match_the_lcm_files() {
        let schema = Schema::coopnav();
        round_trip::<Position>(&schema);
        round_trip::<CnaFix>(&schema);
        round_trip::<StatusFrame>(&schema);
        round_trip::<OwttRange>(&schema);
        round_trip::<CnaCommand>(&schema);
        round_trip::<Decision>(&schema);
        round_trip::<AuvEstimate>(&schema);
        round_trip::<AuvSensors>(&schema);
        round_trip::<Clock>(&schema);
        round_trip::<TeamEstimate>(&schema);
        // Every struct of the schema has a view.
        assert_eq!(schema.structs().len(), 10);
    }

    #[test]
    fn inconsistent_lengths_are_refused_on_encode() {
        let schema = Schema::coopnav();
        let s = AuvSensors { sample_utime: vec![1, 2], sample_velocity: vec![[0.0; 3]], ..AuvSensors::default() };
        assert!(matches!(s.encode(&schema), Err(CodecError::Mismatch { .. })));
        let t = TeamEstimate { auvs: vec![AuvEstimate::default()], names: vec![], ..TeamEstimate::default() };
        assert!(matches!(t.encode(&schema), Err(CodecError::Mismatch { .. })));
        let big = TeamEstimate { auvs: vec![AuvEstimate::default(); 128], ..TeamEstimate::default() };
        assert!(matches!(big.encode(&schema), Err(CodecError::Mismatch { .. })));
    }
}
