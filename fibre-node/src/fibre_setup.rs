//! One fibre of a scene made ready to run: built from its `[[fibre]]` table, checked against
//! the time step (refused with the limit and the cures named), with the values `check` and
//! the summary report for it and the advice it needs.
//!
//! The checks, in the order a scene meets them:
//! - under FPD, a model or sub-stepping FPD cannot move ([`check_fpd_fibre`]);
//! - under SPM's explicit exchange, beads too light for their profile's fluid
//!   ([`spm_exchange::check`]);
//! - the fibre's own stiffness against the time step: the explicit FPD coupling's limit, or
//!   the beam-stiffness limit of the symplectic sub-steps ([`stability`](crate::stability));
//! - under SPM's explicit exchange, the fibre's stiffness against the fluid in its beads'
//!   profiles ([`spm_exchange_stiffness::check`]).
use crate::config::{Coupling, FibreConfig, FibreGroup, ModelKind, SceneConfig, MAX_SUBSTEPS};
use crate::fibre::{Fibre, Model};
use crate::spm_exchange::ExchangeRatios;
use crate::stability::{fpd_margin, fpd_stiffness_limit, stability_limit, StabilityLimit, SAFETY};
use crate::{spm_exchange, spm_exchange_stiffness};
use cosim::profile::DEFAULT_FPD_INTERFACE_RATIO;
use cosim::scene_keys::{AtMost, Num, Sig};

/// A fibre ready to run and what its set-up tells the user.
pub(crate) struct FibreSetup {
    pub fibre: Fibre,
    /// Time-step limits, named (`check` prints them, the summary lists them).
    pub limits: Vec<(String, f64)>,
    /// Derived values, keyed `fibre.N.*`.
    pub derived: Vec<(String, f64)>,
    /// Advice on a fibre the node runs but may resolve poorly.
    pub notes: Vec<String>,
}

/// Fibre `n` of `scene`, built, checked and described.
pub(crate) fn set_up(
    n: usize,
    cfg: &FibreConfig,
    scene: &SceneConfig,
) -> Result<FibreSetup, String> {
    let fpd = scene.coupling == Coupling::Fpd;
    if fpd {
        check_fpd_fibre(n, cfg)?;
    }
    let (f, exchange) = build(n, cfg, scene)?;
    let mut limits = Vec::new();
    let mut notes = Vec::new();
    let lim = if fpd {
        let lim = fpd_limit(n, cfg, scene, &f)?;
        if lim.dt_limit.is_finite() {
            limits.push((format!("FPD fibre stiffness (fibre.{n})"), lim.dt_limit));
        }
        lim
    } else {
        let lim = beam_limit(n, cfg, scene, &f)?;
        if lim.dt_limit.is_finite() {
            limits.push((format!("beam stiffness (fibre.{n})"), lim.dt_limit));
        }
        lim
    };
    // A mode the once-per-step impulse feeds (spm_exchange_stiffness.rs).
    if let Some(r) = exchange.filter(|_| explicit_exchange_applies(cfg)) {
        let p = format!("fibre.{n}");
        let diffusion = scene
            .fluid_kinematic_viscosity
            .zip(scene.spm_profile)
            .map(|(nu, profile)| nu * scene.dt / (profile.xi * profile.xi));
        let x = spm_exchange_stiffness::check(
            &p,
            (&f, cfg.density),
            lim.omega_max,
            r,
            (scene.dt, diffusion),
        )?;
        if let Some(dt_limit) = x.limit() {
            limits.push((format!("explicit exchange stiffness ({p})"), dt_limit));
        }
        notes.extend(x.note(&p));
    }
    if let Some(profile_fluid) = f.implicit_exchange {
        notes.push(implicit_exchange_note(n, cfg, &f, profile_fluid));
    }
    let derived = derived_values(n, cfg, scene, &f, exchange, &lim);
    Ok(FibreSetup {
        fibre: f,
        limits,
        derived,
        notes,
    })
}

/// Under SPM, the explicit exchange's checks apply: clamped beads do not take the exchange's
/// impulses, so a fully clamped fibre has nothing to destabilise, and the implicit exchange
/// is stable for any ratio.
fn explicit_exchange_applies(cfg: &FibreConfig) -> bool {
    !cfg.implicit_exchange && cfg.clamp.len() != cfg.beads
}

/// The straight fibre with its inertia as the coupling has it, and under SPM the fluid its
/// beads' profiles hold against them (refused where the explicit exchange cannot carry it).
fn build(
    n: usize,
    cfg: &FibreConfig,
    scene: &SceneConfig,
) -> Result<(Fibre, Option<ExchangeRatios>), String> {
    let mut f = Fibre::straight(cfg, scene.dimensions, scene.coupling == Coupling::Spm);
    let exchange = scene.spm_profile.map(|profile| {
        let (r, dims) = (cfg.bead_radius, scene.dimensions as usize);
        if cfg.profile_inertia {
            f.inertia = profile.mass_inertia(cfg.density, r, dims).1;
        }
        if cfg.implicit_exchange {
            let (m, i) = profile.mass_inertia(scene.fluid_density, r, dims);
            f.implicit_exchange = Some([m, i]);
        }
        spm_exchange::ratios(profile, scene.fluid_density, r, dims, f.mass, f.inertia)
    });
    if let Some(r) = exchange.filter(|_| explicit_exchange_applies(cfg)) {
        spm_exchange::check(&format!("fibre.{n}"), r, cfg.density)?;
    }
    if scene.coupling == Coupling::Fpd && !cfg.clamp.is_empty() {
        f.hold_under_fpd(fpd_bead_mass(cfg, scene), scene.dt);
    }
    Ok((f, exchange))
}

/// The fluid mass a 2D FPD bead displaces, rho pi a^2: the inertia of the holding force and
/// of the explicit coupling's limit (under FPD the beads have no inertia of their own).
fn fpd_bead_mass(cfg: &FibreConfig, scene: &SceneConfig) -> f64 {
    scene.fluid_density * std::f64::consts::PI * cfg.bead_radius.powi(2)
}

/// The explicit FPD coupling's limit on the lattice step, or the refusal of a fibre too
/// stiff for it with the factor that makes it fit.
fn fpd_limit(
    n: usize,
    cfg: &FibreConfig,
    scene: &SceneConfig,
    f: &Fibre,
) -> Result<StabilityLimit, String> {
    let fpd_mass = fpd_bead_mass(cfg, scene);
    let r_xi = scene
        .fpd_interface_ratio
        .unwrap_or(DEFAULT_FPD_INTERFACE_RATIO);
    // About the straight chain, on which the thresholds were measured: a bent start raises
    // omega_max but not the stiffness at which the coupling fails (measured,
    // docs/validation/fpd.md).
    let straight_cfg = FibreConfig {
        initial_bend: 0.0,
        ..cfg.clone()
    };
    let straight = Fibre::straight(&straight_cfg, scene.dimensions, false);
    let lim = fpd_stiffness_limit(&straight, fpd_mass, r_xi);
    if scene.dt > lim.dt_limit {
        return Err(too_stiff_for_fpd((n, cfg), scene, f, &lim, fpd_mass, r_xi));
    }
    Ok(lim)
}

/// The keys of fibre `n` that set its stiffness, as its table gives them: the modulus of a
/// cohesive beam; for a bead-spring chain the key each constant comes from (k_s:
/// `stretch_number`, `stretch_stiffness` or `youngs_modulus`; k_b: `bending_number`,
/// `bending_stiffness` or `youngs_modulus`).
fn stiffness_keys(n: usize, cfg: &FibreConfig) -> String {
    if cfg.model != ModelKind::BeadSpring {
        return format!("fibre.{n}.youngs_modulus");
    }
    let source = |number: Option<f64>, stiffness: Option<f64>, names: [&'static str; 2]| {
        if number.is_some() {
            names[0]
        } else if stiffness.is_some() {
            names[1]
        } else {
            "youngs_modulus"
        }
    };
    let k_s = source(
        cfg.stretch_number,
        cfg.stretch_stiffness,
        ["stretch_number", "stretch_stiffness"],
    );
    let k_b = source(
        cfg.bending_number,
        cfg.bending_stiffness,
        ["bending_number", "bending_stiffness"],
    );
    if k_s == k_b {
        format!("fibre.{n}.{k_s}")
    } else {
        format!("fibre.{n}.{k_s} and fibre.{n}.{k_b}")
    }
}

/// The refusal of fibre `n` when its stiffness overflows the frequency estimate (no step to
/// quote), naming the keys that set it.
fn overflowed(n: usize, lim: &StabilityLimit, cfg: &FibreConfig) -> Option<String> {
    if lim.omega_max.is_finite() && lim.step_limit > 0.0 {
        return None;
    }
    let keys = stiffness_keys(n, cfg);
    Some(format!(
        "fibre.{n} is too stiff for any time step: the frequency of its fastest mode overflows \
         (omega_max = {}); lower its stiffness ({keys})",
        Sig(lim.omega_max)
    ))
}

/// The refusal of fibre `n`, whose FPD limit `lim` lies below the lattice step.
fn too_stiff_for_fpd(
    (n, cfg): (usize, &FibreConfig),
    scene: &SceneConfig,
    f: &Fibre,
    lim: &StabilityLimit,
    fpd_mass: f64,
    r_xi: f64,
) -> String {
    if let Some(e) = overflowed(n, lim, cfg) {
        return e;
    }
    // omega^2 is linear in (k_s, k_b), so both scaled by this factor fit.
    let factor = (lim.dt_limit / scene.dt).powi(2);
    let (k_s, k_b) = match &f.model {
        Model::BeadSpring(b) => (b.k_s, b.k_b),
        Model::CohesiveBeam(_) => (f64::NAN, f64::NAN),
    };
    format!(
        "fibre.{n} is too stiff for the explicit FPD coupling (S2023 section II C): \
         with the fluid a bead displaces, rho pi a^2 = {}, as its inertia, its \
         fastest mode has omega_max = {}, stable for time.dt up to {} \
         ({:.3} x 2 / omega_max at fluid.interface_ratio = {}, a measured bound), \
         and the lattice step is {}; scale its \
         stiffness by at most {}: fibre.{n}.stretch_stiffness (k_s = \
         {}) to at most {} and its bending (k_b = {}, or \
         fibre.{n}.bending_number) by the same factor, or raise fluid.density",
        Sig(fpd_mass),
        Sig(lim.omega_max),
        AtMost(lim.dt_limit),
        fpd_margin(r_xi),
        Num(r_xi),
        Num(scene.dt),
        AtMost(factor),
        Sig(k_s),
        AtMost(k_s * factor),
        Sig(k_b),
    )
}

/// The beam-stiffness limit of the symplectic sub-steps, or the refusal of a time step above
/// it with the time step or sub-steps that fit.
fn beam_limit(
    n: usize,
    cfg: &FibreConfig,
    scene: &SceneConfig,
    f: &Fibre,
) -> Result<StabilityLimit, String> {
    let lim = stability_limit(f, cfg.substeps);
    let h = scene.dt / cfg.substeps as f64;
    if h > lim.step_limit * SAFETY {
        return Err(too_large_for_the_beam(n, cfg, scene, &lim));
    }
    Ok(lim)
}

/// The refusal of a time step above fibre `n`'s beam-stiffness limit `lim`.
fn too_large_for_the_beam(
    n: usize,
    cfg: &FibreConfig,
    scene: &SceneConfig,
    lim: &StabilityLimit,
) -> String {
    let h = scene.dt / cfg.substeps as f64;
    if let Some(e) = overflowed(n, lim, cfg) {
        return e;
    }
    let h_ok = lim.step_limit * SAFETY;
    let need = (scene.dt / h_ok).ceil();
    let advice = if need <= MAX_SUBSTEPS as f64 {
        format!(" or raise fibre.{n}.substeps to at least {need}")
    } else {
        String::new()
    };
    format!(
        "time step too large for fibre.{n} (beam stiffness limit): \
         time.dt / fibre.{n}.substeps = {} / {} = {} exceeds the stable fibre step \
         {} (symplectic Euler, omega_max = {}, damping rate {} of the fastest mode, 2 % \
         margin); \
         lower time.dt to at most {}{advice}",
        Num(scene.dt),
        cfg.substeps,
        Sig(h),
        Sig(h_ok),
        Sig(lim.omega_max),
        Sig(lim.damping),
        AtMost(lim.dt_limit)
    )
}

/// The values `check` and the summary report for fibre `n` (`fibre.N.*`).
fn derived_values(
    n: usize,
    cfg: &FibreConfig,
    scene: &SceneConfig,
    f: &Fibre,
    exchange: Option<ExchangeRatios>,
    lim: &StabilityLimit,
) -> Vec<(String, f64)> {
    let p = format!("fibre.{n}");
    let mut derived = vec![
        (format!("{p}.length"), cfg.spacing * (cfg.beads - 1) as f64),
        (format!("{p}.bending_rigidity"), f.bending_rigidity()),
        (format!("{p}.bead_mass"), f.mass),
        (format!("{p}.bead_moment_of_inertia"), f.inertia),
    ];
    if let Some(r) = exchange {
        derived.push((format!("{p}.profile_to_bead_mass"), r.mass));
        derived.push((format!("{p}.profile_to_bead_inertia"), r.inertia));
    }
    // With one sub-step the implicit exchange moves a bead as the explicit one moves a bead
    // carrying its profile's fluid (docs/validation/spm.md, "What the implicit exchange is").
    if let (Some([m_phi, i_phi]), 1) = (f.implicit_exchange, cfg.substeps) {
        derived.push((format!("{p}.effective_bead_mass"), f.mass + m_phi));
        derived.push((
            format!("{p}.effective_bead_moment_of_inertia"),
            f.inertia + i_phi,
        ));
    }
    match &f.model {
        Model::CohesiveBeam(b) => {
            derived.push((format!("{p}.axial_stiffness"), b.axial));
            if let Some(shear) = scene.shear_flow {
                // S2023's K with the chain's k_b = E I / l0 (bead_spring.rs), so that a beam
                // and a bead-spring chain of the same rigidity report one K.
                let kb = f.bending_rigidity() / cfg.spacing;
                let k = FibreGroup::Bending.of(kb, shear, cfg);
                derived.push((format!("{p}.bending_number"), k));
            }
            if !f.planar {
                derived.push((format!("{p}.torsional_rigidity"), b.twist * b.rest_length));
            }
        }
        Model::BeadSpring(b) => {
            derived.push((format!("{p}.stretch_stiffness"), b.k_s));
            derived.push((format!("{p}.bending_stiffness"), b.k_b));
            if let Some(shear) = scene.shear_flow {
                // S2023 eq. 18, K = 2 k_b / (eta_f gamma l_c^2), and section II C,
                // K_s = k_s / (eta_f V0 l0), however the stiffnesses were given.
                let k = FibreGroup::Bending.of(b.k_b, shear, cfg);
                derived.push((format!("{p}.bending_number"), k));
                let ks = FibreGroup::Stretch.of(b.k_s, shear, cfg);
                derived.push((format!("{p}.stretch_number"), ks));
            }
        }
    }
    derived.push((format!("{p}.omega_max"), lim.omega_max));
    derived.push((format!("{p}.substeps"), cfg.substeps as f64));
    derived.push((format!("{p}.affinity"), cfg.affinity));
    derived
}

/// What the implicit exchange does to fibre `n`'s beads: the drag at the new velocity makes
/// the fluid in a bead's profile (`[m_phi, I_phi]`) part of the bead's inertia. With one
/// sub-step a kick is algebraically the explicit exchange with mass M + m_phi; with n
/// sub-steps each kick takes 1/n of the drag, which adds less (docs/validation/spm.md, "What
/// the implicit exchange is").
fn implicit_exchange_note(
    n: usize,
    cfg: &FibreConfig,
    f: &Fibre,
    [m_phi, i_phi]: [f64; 2],
) -> String {
    let per_volume = cfg.density * m_phi / f.mass;
    let how = if cfg.substeps == 1 {
        format!(
            "its translation is that of a bead of mass M + m_phi = {} ({:.3} times its own: \
             fibre.{n}.density = {} moves as {:.4}) under the explicit exchange, its spin that \
             of moment of inertia I + I_phi ({:.3} times). For beads of density rho_p above \
             {per_volume:.4}, fibre.{n}.density = rho_p - {per_volume:.4} gives their mass; \
             lighter ones have no implicit equivalent (the explicit exchange runs beads down to \
             half their profile's fluid in mass and moment of inertia)",
            Sig(f.mass + m_phi),
            1.0 + m_phi / f.mass,
            cfg.density,
            cfg.density + per_volume,
            1.0 + i_phi / f.inertia,
        )
    } else {
        format!(
            "with one sub-step it would move as a bead of mass M + m_phi ({:.3} times its own) \
             under the explicit exchange; with fibre.{n}.substeps = {} each kick takes 1/{} of \
             the drag, and the added inertia is less",
            1.0 + m_phi / f.mass,
            cfg.substeps,
            cfg.substeps,
        )
    };
    format!(
        "fibre.{n}.exchange = \"implicit\": the drag at the new velocity makes the fluid in each \
         bead's smoothed profile part of the bead's inertia: {how} (docs/validation/spm.md, \
         \"What the implicit exchange is\")"
    )
}

/// Bead-spring beads feel no torque from their neighbours, so under SPM, where each bead is a
/// rigid body turning with the fluid, the chain is a train of rollers (docs/validation/spm.md,
/// "Flexible versus rigid"; fpd.md, "S2023's Fig. 7 scene"). The note for fibre `n`, where
/// that is so.
pub(crate) fn rollers_note(n: usize, f: &Fibre, coupling: Coupling) -> Option<String> {
    let rollers = coupling == Coupling::Spm
        && matches!(f.model, Model::BeadSpring(_))
        && f.len() > 2
        && f.rotates
        && !f.spin_with_chord;
    rollers.then(|| {
        format!(
            "fibre.{n} (bead-spring under spm): its beads take no torque from each \
             other, so each turns freely with the fluid and the chain moves like a \
             train of rollers: it turns like a slimmer body and bends less than a \
             solid fibre of the same bending rigidity (2D Stokes: 2-80 times less \
             S-shaped moment; on S2023's Fig. 7 scene a tenth as much at the \
             vertical, and it sticks where the cohesive beam tumbles; \
             docs/validation/spm.md). For a solid fibre, use \
             fibre.{n}.model = \"cohesive-beam\", or fibre.{n}.bead_spin = \
             \"chord\""
        )
    })
}

/// What FPD cannot move: a fibre made of bead rotations, or sub-steps between lattice steps.
fn check_fpd_fibre(n: usize, cfg: &FibreConfig) -> Result<(), String> {
    if cfg.model == ModelKind::CohesiveBeam {
        return Err(format!(
            "fibre.{n}.model = \"cohesive-beam\" cannot run under fluid.method = \"fpd-lbm\": \
             FPD moves bead centres with the flow (S2023 eq. 5) and gives no bead rotation, \
             which the cohesive beam's bending and twist are made of; use \
             model = \"bead-spring\" (S2023 section II B)"
        ));
    }
    if cfg.substeps != 1 {
        return Err(format!(
            "fibre.{n}.substeps = {}: under fluid.method = \"fpd-lbm\" the beads move with the \
             flow, one position update per lattice step (S2023 section II C); set it to 1",
            cfg.substeps
        ));
    }
    Ok(())
}
