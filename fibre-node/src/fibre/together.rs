//! All fibres of a scene through one phase in lockstep, for the contact between them
//! ([`crate::fibre_contact`]).
//!
//! Each fibre's phase is the one [`Fibre::advance_positions`] and
//! [`Fibre::advance_velocities`] take alone (module documentation of [`crate::fibre`]): the
//! same drifts, force evaluations and kicks in the same order. Only the sub-steps of all
//! fibres are interleaved, and the contact forces are refreshed from every fibre's positions
//! before each force evaluation, so a bead feels the other fibres where they are at that
//! sub-step. The fibres must take the same number of sub-steps (checked at configure).
use super::{Fibre, HydroKick};
use crate::fibre_contact::FibreContact;
use cosim::BeadImpulse;

/// The contact forces at the current positions, then every fibre's forces.
pub fn compute_forces(fibres: &mut [Fibre], contact: &mut FibreContact) {
    contact.apply(fibres);
    for f in fibres.iter_mut() {
        f.compute_forces();
    }
}

/// `substeps` drifts with the kicks in between, for all fibres at once; ends with the forces
/// at the new positions. `hydro(k)`: what fibre `k`'s kicks carry.
fn sub_steps<'a>(
    fibres: &mut [Fibre],
    contact: &mut FibreContact,
    dt: f64,
    hydro: &dyn Fn(usize) -> HydroKick<'a>,
) {
    let n = fibres.first().map_or(1, |f| f.substeps);
    debug_assert!(fibres.iter().all(|f| f.substeps == n));
    let h = dt / n as f64;
    for s in 0..n {
        for f in fibres.iter_mut() {
            f.drift(h);
        }
        if s + 1 < n {
            compute_forces(fibres, contact);
            for (k, f) in fibres.iter_mut().enumerate() {
                f.kick(h, hydro(k));
            }
        }
    }
    compute_forces(fibres, contact);
}

/// Phase `FibrePositions` for all fibres ([`Fibre::advance_positions`]).
pub fn advance_positions(fibres: &mut [Fibre], contact: &mut FibreContact, dt: f64) {
    // Every fibre of a scene has the same fluid and (here) the same sub-steps, so all or
    // none take the predictor.
    let mut hydro = HydroKick::None;
    for f in fibres.iter_mut() {
        hydro = f.begin_positions();
    }
    sub_steps(fibres, contact, dt, &|_| hydro);
    for f in fibres.iter_mut() {
        f.end_positions();
    }
}

/// Phase `FibreVelocities` for all fibres ([`Fibre::advance_velocities`]); `impulses` holds
/// all fibres' beads in order, `offsets[k]..offsets[k + 1]` fibre `k`'s.
pub fn advance_velocities(
    fibres: &mut [Fibre],
    contact: &mut FibreContact,
    dt: f64,
    impulses: Option<&[BeadImpulse]>,
    offsets: &[usize],
    forces_current: bool,
) {
    let slice = |k: usize| impulses.map(|j| &j[offsets[k]..offsets[k + 1]]);
    let mut corrects = false;
    for (k, f) in fibres.iter_mut().enumerate() {
        let c = f.begin_velocities(slice(k)).is_some();
        debug_assert!(
            k == 0 || c == corrects,
            "the fibres disagree on the corrector"
        );
        corrects = c;
    }
    let n = fibres.first().map_or(1, |f| f.substeps);
    let h = dt / n as f64;
    let hydro = |k: usize| match slice(k) {
        Some(j) if corrects => HydroKick::Share(j, 1.0 / n as f64),
        Some(j) => HydroKick::Share(j, 1.0),
        None => HydroKick::None,
    };
    if corrects {
        sub_steps(fibres, contact, dt, &hydro);
    } else if !forces_current {
        compute_forces(fibres, contact);
    }
    for (k, f) in fibres.iter_mut().enumerate() {
        f.kick(h, hydro(k));
        f.end_velocities(slice(k));
    }
}
