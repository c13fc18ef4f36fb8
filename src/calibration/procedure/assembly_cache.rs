//! The propagation's memory of its assemblies ([`super::pipeline`]'s `derived_sigma`): the
//! covariance propagation assembles the joint models once per column of every axis fit's
//! covariance and per coupling parameter, each from nearly the data of the calibration. What
//! does not change between those assemblies is computed once and reused, bit for bit the same:
//! the recording assembly (the calibration's own data) records each fitted coupling
//! ([`RecordedCoupling`]), its inputs and the driving joints' inverted transmissions; the warm
//! refits of the columns read them back, and keep the gear couplings' start weights by driving
//! angles. The calibration's own assembly uses no cache.

use super::CouplingReport;
use super::recorded_coupling::RecordedCoupling;
use crate::kinematics::PhiRow;
use crate::robot::{CouplingFunction, Transmission};
use nalgebra::Isometry3;
use std::cell::RefCell;

/// What one assembly does with the cache: the recording assembly fills it, the warm refits
/// read it (and keep their gear starts in it).
#[derive(Clone, Copy)]
pub(super) enum CacheUse<'a> {
    /// The assembly of the calibration's data: records every fitted coupling and its inputs.
    Record(&'a AssemblyCache),
    /// A warm refit of a propagation column: reuses what the recording assembly recorded.
    Reuse(&'a AssemblyCache),
}

impl<'a> CacheUse<'a> {
    /// The cache when this assembly records into it.
    pub(super) fn recording(self) -> Option<&'a AssemblyCache> {
        match self {
            CacheUse::Record(cache) => Some(cache),
            CacheUse::Reuse(_) => None,
        }
    }

    /// The cache when this assembly reuses it.
    pub(super) fn reusing(self) -> Option<&'a AssemblyCache> {
        match self {
            CacheUse::Record(_) => None,
            CacheUse::Reuse(cache) => Some(cache),
        }
    }

    /// The cache, either way.
    pub(super) fn cache(self) -> &'a AssemblyCache {
        match self {
            CacheUse::Record(cache) | CacheUse::Reuse(cache) => cache,
        }
    }
}

/// The recorded couplings and the values the assemblies of one propagation share.
#[derive(Default)]
pub(super) struct AssemblyCache {
    /// Every coupling the recording assembly fitted.
    recorded: RefCell<Vec<RecordedCoupling>>,
    /// The couplings' inputs of the recording assembly and their warm refits: a refit whose
    /// inputs are those of the recording (a propagation column that moves another joint's
    /// fit) is computed once and reused.
    memo: RefCell<Vec<CouplingMemo>>,
    /// The driving joints' inverted transmissions at the couplings' sweeps, recorded by the
    /// recording assembly: a column that does not move a driving joint's transmission reuses
    /// them.
    angles: RefCell<Vec<RawAngles>>,
    /// The gear couplings' start weights by raw driving angles: a warm refit's start is their
    /// product with its data, the decomposition done once per driving transmission.
    starts: RefCell<Vec<GearStart>>,
}

/// What a coupling fit depends on besides the fixed data (experiments, second targets,
/// reference pose, controller): the base placement and the rows below the driven joint (its
/// frames), the driving joint's transmission and zero shift.
#[derive(Clone, PartialEq)]
pub(super) struct CouplingInputs {
    pub(super) world_from_base: Isometry3<f64>,
    pub(super) rows: Vec<PhiRow>,
    pub(super) transmission: Option<Transmission>,
    pub(super) shift: f64,
}

/// One coupling's recorded inputs and, once computed, its warm refit on them.
struct CouplingMemo {
    /// Driven joint (0-based).
    k: usize,
    inputs: CouplingInputs,
    refit: Option<(CouplingFunction, CouplingReport)>,
}

/// A driving joint's transmission inverted at a coupling sweep's target-1 commands and at
/// the reference command.
struct RawAngles {
    /// The sweep (experiment index).
    index: usize,
    transmission: Transmission,
    raw: Vec<f64>,
    raw_ref: Option<f64>,
}

/// The weights of a gear coupling's start at one set of raw driving angles.
struct GearStart {
    raw: Vec<f64>,
    weights: Vec<f64>,
}

impl AssemblyCache {
    /// Records a coupling the recording assembly fitted.
    pub(super) fn record_coupling(&self, coupling: RecordedCoupling) {
        self.recorded.borrow_mut().push(coupling);
    }

    /// The couplings recorded, in the order they were fitted (ascending driven joint).
    pub(super) fn take_recorded(&self) -> Vec<RecordedCoupling> {
        self.recorded.take()
    }

    /// The warm refit of the coupling into joint `k` (0-based) on `inputs`, when one was kept.
    pub(super) fn memo_refit(&self, k: usize, inputs: &CouplingInputs) -> Option<(CouplingFunction, CouplingReport)> {
        self.memo
            .borrow()
            .iter()
            .find(|entry| entry.k == k && &entry.inputs == inputs)
            .and_then(|entry| entry.refit.clone())
    }

    /// Keeps `refit` as the warm refit of the coupling into joint `k` on the recorded `inputs`
    /// (nothing when these are not the recorded ones).
    pub(super) fn keep_refit(&self, k: usize, inputs: &CouplingInputs, refit: (CouplingFunction, CouplingReport)) {
        if let Some(entry) = self
            .memo
            .borrow_mut()
            .iter_mut()
            .find(|e| e.k == k && &e.inputs == inputs)
        {
            entry.refit = Some(refit);
        }
    }

    /// Records the inputs the recording assembly fitted the coupling into joint `k` on.
    pub(super) fn record_inputs(&self, k: usize, inputs: CouplingInputs) {
        self.memo.borrow_mut().push(CouplingMemo { k, inputs, refit: None });
    }

    /// The inversions of `transmission` at sweep `index`'s commands and at the reference
    /// command, when recorded.
    pub(super) fn raw_angles(&self, index: usize, transmission: &Transmission) -> Option<(Vec<f64>, Option<f64>)> {
        self.angles
            .borrow()
            .iter()
            .find(|a| a.index == index && &a.transmission == transmission)
            .map(|a| (a.raw.clone(), a.raw_ref))
    }

    /// Records the inversions `raw` (and `raw_ref`) of `transmission` at sweep `index`.
    pub(super) fn record_raw_angles(
        &self,
        index: usize,
        transmission: &Transmission,
        (raw, raw_ref): (&[f64], Option<f64>),
    ) {
        self.angles.borrow_mut().push(RawAngles {
            index,
            transmission: transmission.clone(),
            raw: raw.to_vec(),
            raw_ref,
        });
    }

    /// `f` of the gear start weights at the raw driving angles `raw`, computed by `weights`
    /// the first time these angles are seen.
    pub(super) fn with_gear_weights<T>(
        &self,
        raw: &[f64],
        weights: impl FnOnce() -> Vec<f64>,
        f: impl FnOnce(&[f64]) -> T,
    ) -> T {
        let mut starts = self.starts.borrow_mut();
        let at = match starts.iter().position(|s| s.raw == raw) {
            Some(at) => at,
            None => {
                starts.push(GearStart {
                    raw: raw.to_vec(),
                    weights: weights(),
                });
                starts.len() - 1
            }
        };
        f(&starts[at].weights)
    }
}
