//! Quiet stretches: the truth steps in which no decision falls, no slot starts and no packet is
//! delivered. There the survey AUVs do not touch one another: each one's truth, filter and
//! once-a-second sample read only its own state, its own random streams, the scenario, the
//! bathymetry and the CNA's track (which does not depend on them between decisions). So a
//! stretch runs each AUV through all its steps at once, the fleet split over two threads, and
//! then tells the observer what happened in the order the step-by-step loop would have: the
//! results are the same bit for bit, on any number of threads.

use super::observe::{DeadReckoning, Observer, Phase, ShipPose, TraceRow};
use super::phases::{sample, SenseStep};
use super::vehicles::SurveyAuv;
use super::{AuvTally, Engine};
use crate::closed_loop::scenario::Scenario;
use coopnav_core::{Bathymetry, Vec3};
use std::ops::Range;

/// Fewer quiet steps than this run step by step (a stretch's hand-over costs about a step).
const MIN_STRETCH: u64 = 3;

/// What one survey AUV did over a stretch, for the observer.
pub(super) struct StretchLog {
    /// Its filter step's readings per truth step (None: a decimated filter skipped it).
    readings: Vec<Option<DeadReckoning>>,
    /// Its sample at each whole second of the stretch.
    rows: Vec<TraceRow>,
    finite: bool,
}

/// What every AUV of a stretch shares, read-only.
struct Shared<'a> {
    sc: &'a Scenario,
    bathy: &'a Bathymetry,
    steps: Range<u64>,
    /// The CNA's true position at the end of each step of the stretch.
    cna: &'a [Vec3],
    /// The CNA's model of each AUV's error (it changes only at decisions and deliveries).
    modelled: Vec<Option<f64>>,
    per_second: u64,
}

impl Engine<'_> {
    /// The end of the quiet stretch starting at `step` (≤ `steps`): the first step at which a
    /// phase other than advance, sense and observe has something to do.
    pub(super) fn quiet_until(&self, step: u64, steps: u64) -> u64 {
        (step..steps)
            .find(|&s| {
                let t_next = s as f64 * self.sc.dt + self.sc.dt;
                self.decision_due(t_next) || self.next_slot_before(t_next).is_some() || self.air.any_due(t_next)
            })
            .unwrap_or(steps)
    }

    /// Truth steps per second: the observe phase samples at the end of every `per_second`-th.
    pub(super) fn per_second(&self) -> u64 {
        ((1.0 / self.sc.dt).round() as u64).max(1)
    }

    /// Runs the quiet steps `steps` if there are enough of them to share out (true), else leaves
    /// them to the step-by-step loop (false).
    pub(super) fn try_stretch(&mut self, steps: Range<u64>, obs: &mut dyn Observer) -> bool {
        if steps.end < steps.start + MIN_STRETCH {
            return false;
        }
        let sc = self.sc;
        let cna: Vec<Vec3> = steps
            .clone()
            .map(|_| {
                self.cna.craft.step(sc.cna.speed, sc.cna.max_turn_rate_deg_s.to_radians(), sc.dt);
                self.cna.craft.pos
            })
            .collect();
        let shared = Shared {
            sc,
            bathy: &self.bathy,
            steps: steps.clone(),
            cna: &cna,
            modelled: (0..self.auvs.len()).map(|k| self.cna.model.total(k)).collect(),
            per_second: self.per_second(),
        };
        let n = (steps.end - steps.start) as usize;
        let mut logs: Vec<StretchLog> = self
            .auvs
            .iter()
            .map(|_| StretchLog {
                readings: Vec::with_capacity(n),
                rows: Vec::with_capacity(n / shared.per_second as usize + 1),
                finite: true,
            })
            .collect();
        let mut fleet: Vec<(usize, (&mut SurveyAuv, &mut AuvTally), &mut StretchLog)> = self
            .auvs
            .iter_mut()
            .zip(self.tallies.iter_mut())
            .zip(logs.iter_mut())
            .enumerate()
            .map(|(k, (auv, log))| (k, auv, log))
            .collect();
        share_out(&mut fleet, &shared);
        self.replay(&steps, &cna, &logs, obs);
        true
    }

    /// The stretch's observer calls in step order: the ships' poses (the ships step here), the
    /// filters' readings and, at each whole second, the samples.
    fn replay(&mut self, steps: &Range<u64>, cna: &[Vec3], logs: &[StretchLog], obs: &mut dyn Observer) {
        let sc = self.sc;
        let per_second = self.per_second();
        let mut second = 0;
        for (i, step) in steps.clone().enumerate() {
            let t_next = step as f64 * sc.dt + sc.dt;
            for (ship, (s, spec)) in self.ships.iter_mut().zip(&sc.ships).enumerate() {
                s.step(spec, sc.dt);
                obs.on_ship_pose(&ShipPose { t: t_next, ship, pos: s.pos, heading: s.psi });
            }
            logs.iter().filter_map(|log| log.readings[i].as_ref()).for_each(|dr| obs.on_dead_reckoning(dr));
            if (step + 1) % per_second == 0 {
                let rows: Vec<TraceRow> = logs.iter().map(|log| log.rows[second]).collect();
                self.observe_surroundings(t_next, obs);
                obs.on_sample(t_next, cna[i], &rows);
                second += 1;
            }
        }
        self.finite &= logs.iter().all(|log| log.finite);
        obs.on_phase_end(Phase::Stretch);
    }
}

/// Runs every AUV of `fleet` through the stretch. On a thread of rayon's pool (the benchmark's
/// and the Monte Carlo's runs) the second half is a job the other thread may take while this
/// one runs the first (if none does, this one runs it after). Outside the pool the whole fleet
/// runs here: handing a job into the pool would cost this thread a sleep and a wake-up every
/// stretch, which measured more than the stretch saves.
fn share_out(fleet: &mut [(usize, (&mut SurveyAuv, &mut AuvTally), &mut StretchLog)], shared: &Shared) {
    let run = |part: &mut [(usize, (&mut SurveyAuv, &mut AuvTally), &mut StretchLog)]| {
        part.iter_mut().for_each(|(k, auv, log)| shared.run(*k, auv, log))
    };
    if rayon::current_thread_index().is_none() {
        return run(fleet);
    }
    let (here, there) = fleet.split_at_mut(fleet.len().div_ceil(2));
    rayon::join(|| run(here), || run(there));
}

impl Shared<'_> {
    /// AUV `k` through every step of the stretch: truth, filter, and its sample each whole second.
    fn run(&self, k: usize, (a, tally): &mut (&mut SurveyAuv, &mut AuvTally), log: &mut StretchLog) {
        for (i, step) in self.steps.clone().enumerate() {
            let t_next = step as f64 * self.sc.dt + self.sc.dt;
            a.advance(self.sc, self.bathy);
            log.readings.push(SenseStep::new(self.sc, step, t_next).sense(self.sc, k, a));
            if (step + 1) % self.per_second == 0 {
                log.finite &= a.finite();
                log.rows.push(sample(self.sc, (k, a, tally), t_next, self.cna[i], self.modelled[k]));
            }
        }
    }
}
