//! The sweep's columnar results: the runs table (one row per run and survey AUV) and the fleet
//! table (one row per run), each column typed, written as CSV ([`Table::csv`]) and as Parquet
//! ([`Table::parquet`], with the Apache Arrow crates: a nullable Int64, Float64, Boolean or Utf8
//! column each). `docs/sweeps.md` documents every column.
//!
//! A failed run has one row in each table with its `error` and every metric empty (null).

use crate::expand::Cell;
use crate::plan::Plan;
use crate::shard::{Outcome, Record};
use coopnav_core::run_seed;
use coopnav_sim::models::metrics::AuvMetrics;
use coopnav_sim::observe::metrics::RunResult;

/// A column's values, one per row, None where the row has none.
#[derive(Debug, Clone, PartialEq)]
pub enum Values {
    Int(Vec<Option<i64>>),
    Float(Vec<Option<f64>>),
    Bool(Vec<Option<bool>>),
    Text(Vec<Option<String>>),
}

impl Values {
    fn len(&self) -> usize {
        match self {
            Values::Int(v) => v.len(),
            Values::Float(v) => v.len(),
            Values::Bool(v) => v.len(),
            Values::Text(v) => v.len(),
        }
    }

    fn cell(&self, i: usize) -> String {
        match self {
            Values::Int(v) => v[i].map_or(String::new(), |x| x.to_string()),
            Values::Float(v) => v[i].map_or(String::new(), |x| x.to_string()),
            Values::Bool(v) => v[i].map_or(String::new(), |x| x.to_string()),
            Values::Text(v) => v[i].clone().unwrap_or_default(),
        }
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct Column {
    pub name: String,
    pub values: Values,
}

#[derive(Debug, Clone, PartialEq, Default)]
pub struct Table {
    pub columns: Vec<Column>,
}

impl Table {
    pub fn rows(&self) -> usize {
        self.columns.first().map_or(0, |c| c.values.len())
    }

    /// The table as CSV (a header of the column names; an empty field for a null).
    pub fn csv(&self) -> Result<Vec<u8>, csv::Error> {
        let mut w = csv::Writer::from_writer(Vec::new());
        w.write_record(self.columns.iter().map(|c| c.name.as_str()))?;
        for i in 0..self.rows() {
            w.write_record(self.columns.iter().map(|c| c.values.cell(i)))?;
        }
        w.into_inner().map_err(|e| csv::Error::from(e.into_error()))
    }

    /// The table as one Parquet file (one row group, snappy-compressed pages).
    pub fn parquet(&self) -> Result<Vec<u8>, parquet::errors::ParquetError> {
        use arrow_array::{ArrayRef, BooleanArray, Float64Array, Int64Array, RecordBatch, StringArray};
        use arrow_schema::{DataType, Field, Schema};
        let mut fields = Vec::new();
        let mut arrays: Vec<ArrayRef> = Vec::new();
        for c in &self.columns {
            let (kind, array): (DataType, ArrayRef) = match &c.values {
                Values::Int(v) => (DataType::Int64, std::sync::Arc::new(Int64Array::from(v.clone()))),
                Values::Float(v) => (DataType::Float64, std::sync::Arc::new(Float64Array::from(v.clone()))),
                Values::Bool(v) => (DataType::Boolean, std::sync::Arc::new(BooleanArray::from(v.clone()))),
                Values::Text(v) => (DataType::Utf8, std::sync::Arc::new(StringArray::from(v.clone()))),
            };
            fields.push(Field::new(&c.name, kind, true));
            arrays.push(array);
        }
        let schema = std::sync::Arc::new(Schema::new(fields));
        let batch = if arrays.is_empty() {
            RecordBatch::new_empty(schema.clone())
        } else {
            RecordBatch::try_new(schema.clone(), arrays)?
        };
        let props = parquet::file::properties::WriterProperties::builder()
            .set_compression(parquet::basic::Compression::SNAPPY)
            .set_created_by(format!("coopnav {}", crate::plan::VERSION))
            .build();
        let mut out = Vec::new();
        let mut w = parquet::arrow::ArrowWriter::try_new(&mut out, schema, Some(props))?;
        w.write(&batch)?;
        w.close()?;
        Ok(out)
    }
}

/// Builds a table row by row: each `push_*` appends to its named column, created on first use.
#[derive(Default)]
struct Builder {
    table: Table,
    row: usize,
}

impl Builder {
    fn column(&mut self, name: &str, empty: fn() -> Values) -> &mut Values {
        if let Some(i) = self.table.columns.iter().position(|c| c.name == name) {
            return &mut self.table.columns[i].values;
        }
        self.table.columns.push(Column { name: name.to_string(), values: empty() });
        &mut self.table.columns.last_mut().expect("just pushed").values
    }

    fn int(&mut self, name: &str, v: Option<i64>) {
        if let Values::Int(c) = self.column(name, || Values::Int(Vec::new())) {
            c.push(v);
        }
    }
    fn float(&mut self, name: &str, v: Option<f64>) {
        if let Values::Float(c) = self.column(name, || Values::Float(Vec::new())) {
            c.push(v);
        }
    }
    fn bool(&mut self, name: &str, v: Option<bool>) {
        if let Values::Bool(c) = self.column(name, || Values::Bool(Vec::new())) {
            c.push(v);
        }
    }
    fn text(&mut self, name: &str, v: Option<String>) {
        if let Values::Text(c) = self.column(name, || Values::Text(Vec::new())) {
            c.push(v);
        }
    }

    fn end_row(&mut self) {
        self.row += 1;
        debug_assert!(self.table.columns.iter().all(|c| c.values.len() == self.row), "every column has every row");
    }
}

/// How an axis's values are typed in the tables: integers, numbers, booleans or text.
#[derive(Clone, Copy)]
enum AxisKind {
    Int,
    Float,
    Bool,
    Text,
}

fn axis_kind(cells: &[Cell], k: usize) -> AxisKind {
    let values = || cells.iter().map(|c| &c.labels[k].1);
    if values().all(|v| v.is_integer()) {
        AxisKind::Int
    } else if values().all(|v| v.is_integer() || v.is_float()) {
        AxisKind::Float
    } else if values().all(|v| v.is_bool()) {
        AxisKind::Bool
    } else {
        AxisKind::Text
    }
}

/// The columns every row of both tables starts with: the run, its cell, every axis value, the
/// policy, the run index and seed, and whether it failed.
fn identity(b: &mut Builder, plan: &Plan, kinds: &[AxisKind], id: usize, error: Option<&str>) {
    let at = plan.locate(id);
    let cell = &plan.cells[at.cell];
    b.int("run_id", Some(id as i64));
    b.int("cell", Some(at.cell as i64));
    b.text("scenario", Some(cell.base.clone()));
    for (k, (name, value)) in cell.labels.iter().enumerate() {
        match kinds[k] {
            AxisKind::Int => b.int(name, value.as_integer()),
            AxisKind::Float => b.float(name, value.as_float().or(value.as_integer().map(|i| i as f64))),
            AxisKind::Bool => b.bool(name, value.as_bool()),
            AxisKind::Text => b.text(name, Some(value.as_str().map_or(value.to_string(), str::to_string))),
        }
    }
    b.text("policy", Some(plan.inputs.policies[at.policy].clone()));
    b.int("run", Some(at.run as i64));
    // The seed as the engine used it; u64 stored as i64's bits would mislead, so as text.
    b.text("seed", Some(run_seed(cell.scenario.seed, at.run as u64).to_string()));
    b.text("error", error.map(str::to_string));
}

fn auv_columns(b: &mut Builder, k: Option<usize>, a: Option<&AuvMetrics>) {
    let f = |g: fn(&AuvMetrics) -> f64| a.map(g);
    let u = |g: fn(&AuvMetrics) -> u64| a.map(|a| g(a) as i64);
    b.int("auv", k.map(|k| k as i64));
    b.text("auv_name", a.map(|a| a.name.clone()));
    b.float("error_mean_m", f(|a| a.error.mean));
    b.float("error_rms_m", f(|a| a.error.rms));
    b.float("error_p95_m", f(|a| a.error.p95));
    b.float("error_max_m", f(|a| a.error.max));
    b.float("error_cep50_m", f(|a| a.error.cep50));
    b.float("modelled_mean_m", a.and_then(|a| a.modelled_mean));
    b.int("downlink_sent", u(|a| a.downlink.sent));
    b.int("downlink_received", u(|a| a.downlink.received));
    b.int("downlink_lost_in_air", u(|a| a.downlink.lost_in_air));
    b.int("uplink_sent", u(|a| a.uplink.sent));
    b.int("uplink_received", u(|a| a.uplink.received));
    b.int("uplink_lost_in_air", u(|a| a.uplink.lost_in_air));
    b.int("buoy_sent", u(|a| a.buoy_link.sent));
    b.int("buoy_received", u(|a| a.buoy_link.received));
    b.int("ranges_applied", u(|a| a.ranges_applied));
    b.float("distance_mean_m", f(|a| a.distance_mean));
    b.float("distance_min_m", f(|a| a.distance_min));
    b.float("distance_max_m", f(|a| a.distance_max));
    b.float("limit_violation", f(|a| a.limit_violation));
    b.float("sigma_mean_m", f(|a| a.health.sigma_mean));
    b.float("error_to_sigma", f(|a| a.health.error_to_sigma));
    b.float("nees_mean", f(|a| a.health.nees_mean));
    b.float("nees_in_95", f(|a| a.health.nees_in_95));
    b.float("nis_mean", a.and_then(|a| a.health.nis_mean));
    b.float("nis_in_95", a.and_then(|a| a.health.nis_in_95));
    b.float("diverged_at_s", a.and_then(|a| a.health.diverged_at_s));
}

fn fleet_columns(b: &mut Builder, r: Option<&RunResult>) {
    let f = |g: fn(&RunResult) -> f64| r.map(g);
    b.int("n_auvs", r.map(|r| r.auvs.len() as i64));
    b.float("error_mean_m", f(|r| r.fleet.error.mean));
    b.float("error_rms_m", f(|r| r.fleet.error.rms));
    b.float("error_p95_m", f(|r| r.fleet.error.p95));
    b.float("error_max_m", f(|r| r.fleet.error.max));
    b.float("error_cep50_m", f(|r| r.fleet.error.cep50));
    b.float("modelled_mean_m", r.and_then(|r| r.fleet.modelled_mean));
    b.bool("healthy", r.map(|r| r.fleet.healthy));
    b.int("diverged", r.map(|r| r.fleet.diverged as i64));
    let p = r.and_then(|r| r.planner.as_ref());
    b.int("planner_decisions", p.map(|p| p.decisions as i64));
    b.int("planner_deadline_misses", p.map(|p| p.deadline_misses as i64));
    b.float("planner_mean_levels", p.map(|p| p.mean_levels_searched));
    b.int("planner_failures", p.map(|p| p.failures as i64));
}

/// The runs table and the fleet table of `records` (every run of the plan, in id order).
pub fn tables(plan: &Plan, records: &[Record]) -> (Table, Table) {
    let kinds: Vec<AxisKind> = (0..plan.inputs.axes.len()).map(|k| axis_kind(&plan.cells, k)).collect();
    let (mut runs, mut fleet) = (Builder::default(), Builder::default());
    for rec in records {
        let (result, error) = match &rec.outcome {
            Outcome::Done(r) => (Some(r.as_ref()), None),
            Outcome::Failed(e) => (None, Some(e.as_str())),
        };
        identity(&mut fleet, plan, &kinds, rec.id, error);
        fleet_columns(&mut fleet, result);
        fleet.end_row();
        match result {
            Some(r) => {
                for (k, a) in r.auvs.iter().enumerate() {
                    identity(&mut runs, plan, &kinds, rec.id, None);
                    auv_columns(&mut runs, Some(k), Some(a));
                    runs.end_row();
                }
            }
            None => {
                identity(&mut runs, plan, &kinds, rec.id, error);
                auv_columns(&mut runs, None, None);
                runs.end_row();
            }
        }
    }
    (runs.table, fleet.table)
}
