//! The CNA's end of the rate adaptation (a `rate_policy` on the CNA's slot; without one its
//! broadcast stays at `comms.cna_rate`). The same rate-policy plug-ins the survey AUVs' ends use
//! (`coopnav_acomms::selector`), with two choices the Nams thesis leaves open, both invented
//! (Nams 2014, §5.3.2: the thesis says a mixer for several recipients is needed and does not
//! design one; docs/models.md#nams-selector):
//! - the distance it decides on is the one to the **farthest** survey AUV it has a forecast of
//!   (the CNA's broadcast is every AUV's range; the farthest is the one it must still reach);
//! - a broadcast's outcome is judged by that AUV: success when that AUV's next status decoded at
//!   the CNA acknowledges it, failure when that status does not (Nams's implicit negative,
//!   Nams 2014, §5.2). The acknowledgements ride in the statuses the way the CNA's ride in its
//!   broadcast (one bit per packet, not modelled in the status bytes).

use coopnav_acomms::selector::{Choice, Outcome, RatePolicy, RatePolicyError, RatePolicySpec};

#[derive(Clone)]
pub struct CnaRate {
    selector: Box<dyn RatePolicy>,
    /// Broadcasts sent (the id of the next one).
    sent: u64,
    /// Per survey AUV: the broadcasts judged by it, not yet resolved, with the time by which
    /// their arrival at it has surely ended.
    judged_by: Vec<Vec<(u64, f64)>>,
}

impl CnaRate {
    /// The CNA's policy for a fleet of `n_auvs` (validation has checked the specification).
    pub fn new(spec: &RatePolicySpec, n_auvs: usize) -> Result<Self, RatePolicyError> {
        Ok(CnaRate { selector: spec.build()?, sent: 0, judged_by: vec![Vec::new(); n_auvs] })
    }

    /// Every rate the policy may use.
    pub fn rates(&self) -> Vec<coopnav_acomms::Rate> {
        self.selector.rates()
    }

    /// The choice for the next broadcast, given the distance to the farthest AUV (its index and
    /// distance; None: no forecast of any yet). A broadcast sent is recorded under that AUV,
    /// resolvable after `settled_s` (its air time plus the longest travel time).
    pub fn choose(&mut self, farthest: Option<(usize, f64)>, t_tx: f64, settled_s: f64) -> (u64, Choice) {
        let id = self.sent;
        self.sent += 1;
        let choice = self.selector.choose(id, farthest.map(|f| f.1));
        if let (Choice::Transmit(_), Some((k, _))) = (choice, farthest) {
            self.judged_by[k].push((id, t_tx + settled_s));
        }
        (id, choice)
    }

    /// AUV `k`'s status sent at `t_tx` was decoded, acknowledging the broadcasts in `heard`: every
    /// broadcast judged by `k` whose arrival had ended before that status left is resolved.
    pub fn on_status(&mut self, k: usize, t_tx: f64, heard: &[u64]) {
        let pending = &mut self.judged_by[k];
        let resolved: Vec<Outcome> = pending
            .iter()
            .filter(|(_, settled)| *settled <= t_tx)
            .map(|(id, _)| Outcome { slot: *id, success: heard.contains(id) })
            .collect();
        pending.retain(|(_, settled)| *settled > t_tx);
        self.selector.feedback(&resolved, true);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use coopnav_acomms::Rate;

    #[test]
    fn a_broadcast_is_resolved_by_the_auv_it_was_judged_by_once_its_arrival_ended() {
        let mut cna = CnaRate::new(&RatePolicySpec::Fixed { rate: Rate::R1 }, 2).unwrap();
        let (id, choice) = cna.choose(Some((1, 900.0)), 0.0, 5.0);
        assert_eq!((id, choice), (0, Choice::Transmit(Rate::R1)));
        assert_eq!(cna.judged_by, [vec![], vec![(0, 5.0)]]);
        // Another AUV's status, and AUV 1's sent before the broadcast reached it, resolve nothing.
        cna.on_status(0, 10.0, &[]);
        cna.on_status(1, 4.0, &[]);
        assert_eq!(cna.judged_by[1], [(0, 5.0)]);
        cna.on_status(1, 6.0, &[0]);
        assert!(cna.judged_by[1].is_empty());
        // Without a forecast of any AUV nothing is recorded.
        assert_eq!(cna.choose(None, 20.0, 5.0).0, 1);
        assert!(cna.judged_by.iter().all(Vec::is_empty));
    }
}
