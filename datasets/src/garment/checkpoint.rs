//! Stopping and resuming a sewing and drape (`btf synth garment --resume`): the solver's
//! whole state part-way — positions, velocities, simulated time, step counts, the cloth
//! contact's candidate list with the sides it remembers, the rest criterion's quiet
//! period and the reports of the phases already done — so that a resumed run goes on bit
//! for bit as if it had never stopped (the solver is deterministic; `tests.rs` checks it).
//! Everything before the first sub-step (pattern, mesh, springs) is recomputed from the
//! same inputs, which the snapshot's key fingerprints.
//!
//! The file is little-endian binary behind an 8-byte magic; every count is checked against
//! the bytes left before anything is allocated, so a damaged or foreign file is refused
//! with the field named, never read into a giant allocation.

use crate::sim::step::RestReport;
use crate::vec3::V3;
use crate::{Error, Result};
use std::time::{Duration, Instant};

const MAGIC: &[u8; 8] = b"BTFGARM1";

/// The state of a sewing and drape part-way.
#[derive(Debug, Clone, PartialEq)]
pub struct Snapshot {
    /// Fingerprint of everything that shapes the garment ([`fingerprint`] of the caller's
    /// inputs); a snapshot is resumed only under the same one.
    pub key: u64,
    /// 0 while sewing; `k + 1` during the drape's `k`-th run (the first, then the runs
    /// resumed after smoothing).
    pub phase: u32,
    /// Simulated time (s).
    pub(crate) time: f64,
    /// Simulated time at the start of the current drape run (s).
    pub(crate) run_start: f64,
    /// Sub-steps taken in the current phase.
    pub(crate) steps: u64,
    pub(crate) x: Vec<V3>,
    pub(crate) v: Vec<V3>,
    /// The cloth contact's candidate list (node, triangle, side) and where it was built.
    pub(crate) pairs: Vec<(u32, u32, f64)>,
    pub(crate) built_at: Vec<V3>,
    /// Start of the current quiet period (drape runs).
    pub(crate) quiet_since: Option<f64>,
    /// The sewing's report and seam gap (drape phases).
    pub(crate) sewing: RestReport,
    pub(crate) gap: f64,
    /// The drape runs finished before this one, combined.
    pub(crate) drape: Option<RestReport>,
    pub(crate) untangle_rounds: u64,
}

/// Where snapshots go: `save` gets one every `every` of wall time (and never more often
/// than every 64 sub-steps); `from` is the snapshot to resume.
pub struct Checkpointing<'a> {
    /// Fingerprint of the inputs, written into every snapshot.
    pub key: u64,
    /// Snapshot to resume from (its key must equal `key`).
    pub from: Option<Snapshot>,
    /// Wall time between snapshots.
    pub every: Duration,
    /// Receives the snapshots; an error stops the run.
    pub save: &'a mut dyn FnMut(&Snapshot) -> Result<()>,
    pub(crate) last: Option<Instant>,
}

impl<'a> Checkpointing<'a> {
    /// Snapshots every `every` into `save`, resuming `from`.
    pub fn new(
        key: u64,
        from: Option<Snapshot>,
        every: Duration,
        save: &'a mut dyn FnMut(&Snapshot) -> Result<()>,
    ) -> Result<Self> {
        if let Some(s) = &from
            && s.key != key
        {
            return Err(Error::Invalid(
                "the snapshot was written for other parameters (kind, size, vertices, body, \
                 fabric or drape settings)"
                    .into(),
            ));
        }
        Ok(Checkpointing { key, from, every, save, last: None })
    }

    /// Whether a snapshot is due (the first call starts the clock).
    pub(crate) fn due(&mut self) -> bool {
        let now = Instant::now();
        match self.last {
            None => {
                self.last = Some(now);
                self.every.is_zero()
            }
            Some(t) if now.duration_since(t) >= self.every => {
                self.last = Some(now);
                true
            }
            Some(_) => false,
        }
    }
}

/// FNV-1a over `bytes`: the key of a run's inputs.
pub fn fingerprint(bytes: &[u8]) -> u64 {
    bytes
        .iter()
        .fold(0xcbf2_9ce4_8422_2325u64, |h, &b| (h ^ b as u64).wrapping_mul(0x100_0000_01b3))
}

fn put_report(out: &mut Vec<u8>, r: &RestReport) {
    out.push(r.settled as u8);
    for f in [r.settle_time_s, r.end_time_s, r.kinetic_energy_per_kg] {
        out.extend_from_slice(&f.to_le_bytes());
    }
    for n in [r.steps, r.halvings, r.projected] {
        out.extend_from_slice(&(n as u64).to_le_bytes());
    }
}

impl Snapshot {
    /// The snapshot as bytes.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(64 + 48 * self.x.len() + 24 * self.pairs.len());
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&self.key.to_le_bytes());
        out.extend_from_slice(&self.phase.to_le_bytes());
        for f in [self.time, self.run_start, self.quiet_since.unwrap_or(f64::NAN), self.gap] {
            out.extend_from_slice(&f.to_le_bytes());
        }
        out.extend_from_slice(&self.steps.to_le_bytes());
        out.extend_from_slice(&self.untangle_rounds.to_le_bytes());
        put_report(&mut out, &self.sewing);
        out.push(self.drape.is_some() as u8);
        put_report(&mut out, &self.drape.unwrap_or_default());
        for list in [&self.x, &self.v, &self.built_at] {
            out.extend_from_slice(&(list.len() as u64).to_le_bytes());
            for p in list.iter() {
                for c in p {
                    out.extend_from_slice(&c.to_le_bytes());
                }
            }
        }
        out.extend_from_slice(&(self.pairs.len() as u64).to_le_bytes());
        for &(n, t, s) in &self.pairs {
            out.extend_from_slice(&n.to_le_bytes());
            out.extend_from_slice(&t.to_le_bytes());
            out.extend_from_slice(&s.to_le_bytes());
        }
        out
    }

    /// Reads a snapshot written by [`Snapshot::to_bytes`]; a short, foreign or damaged one
    /// is refused with the field at fault named.
    pub fn from_bytes(bytes: &[u8]) -> Result<Snapshot> {
        let mut r = Reader { bytes, at: 0 };
        if r.take(8, "magic")? != MAGIC {
            return Err(Error::Invalid("not a garment snapshot (magic)".into()));
        }
        let key = r.u64("key")?;
        let phase = u32::from_le_bytes(r.take(4, "phase")?.try_into().unwrap());
        let time = r.f64("time")?;
        let run_start = r.f64("run start")?;
        let quiet = r.f64("quiet since")?;
        let gap = r.f64("seam gap")?;
        let steps = r.u64("steps")?;
        let untangle_rounds = r.u64("smoothing rounds")?;
        let sewing = r.report("sewing report")?;
        let has_drape = r.take(1, "drape flag")?[0] != 0;
        let drape = r.report("drape report")?;
        let x = r.points("positions")?;
        let v = r.points("velocities")?;
        let built_at = r.points("contact list positions")?;
        let n = r.count(16, "contact pairs")?;
        let mut pairs = Vec::with_capacity(n);
        for _ in 0..n {
            let node = u32::from_le_bytes(r.take(4, "contact pair")?.try_into().unwrap());
            let tri = u32::from_le_bytes(r.take(4, "contact pair")?.try_into().unwrap());
            pairs.push((node, tri, r.f64("contact side")?));
        }
        if r.at != bytes.len() {
            return Err(Error::Invalid(format!(
                "garment snapshot: {} bytes after the contact pairs",
                bytes.len() - r.at
            )));
        }
        if v.len() != x.len() {
            return Err(Error::Invalid(format!(
                "garment snapshot: {} velocities for {} positions",
                v.len(),
                x.len()
            )));
        }
        if !x.iter().chain(&v).chain(&built_at).all(|p| p.iter().all(|c| c.is_finite()))
            || ![time, run_start, gap].iter().all(|t| t.is_finite())
            || !(quiet.is_nan() || quiet.is_finite())
        {
            return Err(Error::Invalid(
                "garment snapshot: a non-finite position, velocity, time, quiet-period start or \
                 gap"
                .into(),
            ));
        }
        if let Some(&(node, tri, side)) = pairs.iter().find(|p| ![-1.0, 0.0, 1.0].contains(&p.2)) {
            return Err(Error::Invalid(format!(
                "garment snapshot: contact pair (node {node}, triangle {tri}) has side {side}, \
                 not −1, 0 or 1"
            )));
        }
        Ok(Snapshot {
            key,
            phase,
            time,
            run_start,
            steps,
            x,
            v,
            pairs,
            built_at,
            quiet_since: (!quiet.is_nan()).then_some(quiet),
            sewing,
            gap,
            drape: has_drape.then_some(drape),
            untangle_rounds,
        })
    }
}

struct Reader<'b> {
    bytes: &'b [u8],
    at: usize,
}

impl<'b> Reader<'b> {
    fn take(&mut self, n: usize, what: &str) -> Result<&'b [u8]> {
        if self.bytes.len() - self.at < n {
            return Err(Error::Invalid(format!("garment snapshot ends inside its {what}")));
        }
        self.at += n;
        Ok(&self.bytes[self.at - n..self.at])
    }
    fn u64(&mut self, what: &str) -> Result<u64> {
        Ok(u64::from_le_bytes(self.take(8, what)?.try_into().unwrap()))
    }
    fn f64(&mut self, what: &str) -> Result<f64> {
        Ok(f64::from_le_bytes(self.take(8, what)?.try_into().unwrap()))
    }
    /// A count of items of `size` bytes each, refused when the bytes left cannot hold them.
    fn count(&mut self, size: usize, what: &str) -> Result<usize> {
        let n = self.u64(what)?;
        let left = (self.bytes.len() - self.at) as u64;
        if n > left / size as u64 {
            return Err(Error::Invalid(format!(
                "garment snapshot: {n} {what} do not fit in the {left} bytes left"
            )));
        }
        Ok(n as usize)
    }
    fn points(&mut self, what: &str) -> Result<Vec<V3>> {
        let n = self.count(24, what)?;
        (0..n).map(|_| Ok([self.f64(what)?, self.f64(what)?, self.f64(what)?])).collect()
    }
    fn report(&mut self, what: &str) -> Result<RestReport> {
        let settled = self.take(1, what)?[0] != 0;
        let settle_time_s = self.f64(what)?;
        let end_time_s = self.f64(what)?;
        let kinetic_energy_per_kg = self.f64(what)?;
        let steps = self.u64(what)? as usize;
        let halvings = self.u64(what)? as usize;
        let projected = self.u64(what)? as usize;
        Ok(RestReport {
            settled,
            settle_time_s,
            end_time_s,
            steps,
            halvings,
            projected,
            kinetic_energy_per_kg,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Snapshot {
        Snapshot {
            key: 7,
            phase: 2,
            time: 1.25,
            run_start: 0.5,
            steps: 640,
            x: vec![[0.0, 1.0, 2.0], [3.0, 4.0, 5.0]],
            v: vec![[0.1, 0.2, 0.3], [0.4, 0.5, 0.6]],
            pairs: vec![(0, 1, -1.0), (1, 0, 0.0)],
            built_at: vec![[0.0; 3], [1.0; 3]],
            quiet_since: Some(0.75),
            sewing: RestReport { settled: true, steps: 12, ..Default::default() },
            gap: 1e-3,
            drape: None,
            untangle_rounds: 3,
        }
    }

    /// A snapshot reads back as written; cut short anywhere, or with a count larger than
    /// the bytes left, it is refused with a message (no panic, no giant allocation).
    #[test]
    fn snapshots_round_trip_and_damaged_ones_are_refused() {
        let s = sample();
        let bytes = s.to_bytes();
        assert_eq!(Snapshot::from_bytes(&bytes).unwrap(), s);
        for cut in [0, 7, 8, 30, bytes.len() / 2, bytes.len() - 1] {
            let e = Snapshot::from_bytes(&bytes[..cut]).unwrap_err().to_string();
            assert!(e.contains("snapshot"), "cut at {cut}: {e}");
        }
        // The positions' count (right after the two reports) made huge.
        let at = 8 + 8 + 4 + 4 * 8 + 8 + 8 + 49 + 1 + 49;
        let mut bad = bytes.clone();
        bad[at..at + 8].copy_from_slice(&u64::MAX.to_le_bytes());
        let e = Snapshot::from_bytes(&bad).unwrap_err().to_string();
        assert!(e.contains("positions") && e.contains("do not fit"), "{e}");
        // A NaN velocity, and a contact side that is not ±1 or 0 (the last 8 bytes).
        let mut nan = bytes.clone();
        let v0 = at + 8 + 2 * 24 + 8;
        nan[v0..v0 + 8].copy_from_slice(&f64::NAN.to_le_bytes());
        assert!(Snapshot::from_bytes(&nan).unwrap_err().to_string().contains("non-finite"));
        let mut side = bytes.clone();
        let n = side.len();
        side[n - 8..].copy_from_slice(&0.5f64.to_le_bytes());
        assert!(Snapshot::from_bytes(&side).unwrap_err().to_string().contains("side 0.5"));
        // The quiet period's start: none (NaN on disk) reads back as none; infinite is
        // refused (a rest declared at an infinite time).
        let none = Snapshot { quiet_since: None, ..sample() };
        assert_eq!(Snapshot::from_bytes(&none.to_bytes()).unwrap(), none);
        let mut inf = bytes.clone();
        let q = 8 + 8 + 4 + 8 + 8;
        inf[q..q + 8].copy_from_slice(&f64::INFINITY.to_le_bytes());
        assert!(Snapshot::from_bytes(&inf).unwrap_err().to_string().contains("quiet-period"));
        let mut foreign = bytes;
        foreign[0] = b'X';
        assert!(Snapshot::from_bytes(&foreign).unwrap_err().to_string().contains("magic"));
    }
}
