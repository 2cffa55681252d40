//! Multiple-relaxation-time lattice Boltzmann D2Q9 solver (Lallemand & Luo 2000; REFERENCE.md
//! section 5) with a per-node viscosity and a per-node body force: the flow solver of the
//! fluid particle dynamics method on MRT-LBM of S2023 (Su et al. 2023, section II C), where a
//! solid is a fluid of high viscosity, eta = eta_f + (eta_s - eta_f) phi (S2023 eq. 1).
//!
//! Lattice units (dx = dt = 1, c_s^2 = 1/3). The lattice is `nx` x `ny` nodes, node (x, y) at
//! integer coordinates, periodic in x. In y either periodic or closed by two walls with
//! half-way bounce-back: the walls' planes lie halfway along the cut links, at y = -1/2 and
//! y = ny - 1/2, and each wall slides along x at its own speed u_w, which enters as
//! f_opp(x_f) = f_i*(x_f) - 2 w_i rho (c_i . u_w) / c_s^2 (REFERENCE.md section 5), rho the
//! density of the fluid node x_f.
//!
//! Collision (see [`kernel::collide`]): m* = m - S(m - m_eq) + (I - S/2) F_hat with Guo's
//! forcing in moment space and rho u = sum f c + F/2. Per node, s_nu = 1/(3 nu + 1/2) from
//! the local viscosity, and s_q from Lambda = (1/s_nu - 1/2)(1/s_q - 1/2) = 3/16, which puts
//! the bounce-back wall exactly at the link midpoint whatever the viscosity: the momentum of
//! plane Couette and Poiseuille flows is then exact, the velocity up to the O(Ma^2) density
//! variation across the channel. The two remaining even moments relax at fixed rates
//! s_e = s_eps = 1.1 by default ([`FixedRates`]): they carry no shear stress, and a rate
//! near one damps their non-hydrodynamic modes quickly without touching the channel
//! solutions above.
//!
//! Layout and scheme. The populations are stored row by row, each row holding nine
//! contiguous sub-rows of `nx` values, one per velocity (`[y][i][x]`). One step is a fused
//! "pull": every node gathers the post-collision populations of its upstream neighbours
//! (streaming), collides, and writes its own nine post-collision values into the second
//! lattice; then the lattices swap. Writing only its own row makes the row-parallel loop
//! safe without shared mutable state; within a row the streaming shift in x is a contiguous
//! offset read of a sub-row, which vectorises, where an array of structures would interleave
//! the nine velocities. The stored values are thus the post-collision populations of the last
//! step; the populations "at time t" (and the density and velocity reported) are those
//! gathered from them, exactly as the next step sees them. What is stored is the deviation
//! f - w rho0 from the rest state (Skordos 1993): its round-off scales with the flow, not with
//! rho0, which keeps the mass to round-off of the deviations and small velocities precise.
//!
//! Plan once, step many times: [`MrtD2q9::new`] validates a [`MrtConfig`] and allocates all
//! storage; [`MrtD2q9::step`] allocates nothing.
pub mod kernel;

use crate::parallel::{min_len, ordered_sum, per_row};
use kernel::{collide, collide_with_velocity, macroscopic, C, OPP, Q, W};
pub use kernel::{s_nu, s_q, FixedRates};
use rayon::prelude::*;

/// Smallest number of nodes along x and along y.
pub const MIN_SIZE: usize = 2;

/// What closes the lattice in y.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum YBoundary {
    /// Periodic in y as in x.
    Periodic,
    /// Half-way bounce-back walls at y = -1/2 (`bottom`) and y = ny - 1/2 (`top`), sliding
    /// along x at the given velocities (lattice units).
    Walls { bottom: f64, top: f64 },
}

/// Everything [`MrtD2q9::new`] needs. Fields can be set directly; [`MrtConfig::new`] gives
/// the defaults (density 1 at rest, [`FixedRates::default`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MrtConfig {
    pub nx: usize,
    pub ny: usize,
    pub y_boundary: YBoundary,
    /// Initial uniform kinematic viscosity (lattice units); a field replaces it with
    /// [`MrtD2q9::set_viscosity`].
    pub viscosity: f64,
    /// Initial uniform density (the fluid starts at rest), also the reference density rho0
    /// whose rest populations w_i rho0 are subtracted in storage.
    pub density: f64,
    pub fixed_rates: FixedRates,
}

impl MrtConfig {
    pub fn new(nx: usize, ny: usize, y_boundary: YBoundary, viscosity: f64) -> Self {
        Self {
            nx,
            ny,
            y_boundary,
            viscosity,
            density: 1.0,
            fixed_rates: FixedRates::default(),
        }
    }
}

impl Default for FixedRates {
    fn default() -> Self {
        Self {
            s_e: 1.1,
            s_eps: 1.1,
        }
    }
}

/// Check that a viscosity gives relaxation rates s_nu and s_q strictly inside (0, 2).
pub fn check_viscosity(nu: f64) -> Result<(), String> {
    if !(nu.is_finite() && nu > 0.0) {
        return Err(format!(
            "viscosity {} is not a finite positive number",
            cosim::scene_keys::Num(nu)
        ));
    }
    let (sn, sq) = (s_nu(nu), s_q(nu));
    for (name, s) in [("s_nu", sn), ("s_q", sq)] {
        if !(s > 0.0 && s < 2.0) {
            return Err(format!(
                "viscosity {} gives the relaxation rate {name} = {s}, outside (0, 2)",
                cosim::scene_keys::Num(nu)
            ));
        }
    }
    Ok(())
}

fn check_wall_speed(name: &str, u: f64) -> Result<(), String> {
    // Beyond the lattice sound speed the scheme has no meaning.
    if !(u.is_finite() && u.abs() < 1.0 / 3f64.sqrt()) {
        return Err(format!(
            "{name} wall velocity {u} is not finite or not below the sound speed 1/sqrt(3)"
        ));
    }
    Ok(())
}

/// Sizes and boundaries: copied into the parallel loops, so they borrow nothing.
#[derive(Debug, Clone, Copy)]
struct Geometry {
    nx: usize,
    ny: usize,
    /// Bottom and top wall x-velocities; `None`: periodic in y.
    walls: Option<[f64; 2]>,
    /// Reference density: the lattice stores f - w rho0 ([`kernel::rest_moments`]).
    rho0: f64,
}

impl Geometry {
    /// Index of population `i` of node (x, y) in the `[y][i][x]` layout.
    #[inline(always)]
    fn at(&self, y: usize, i: usize, x: usize) -> usize {
        (y * Q + i) * self.nx + x
    }

    /// v + d (d in -1..=1) modulo n.
    #[inline(always)]
    fn wrap(n: usize, v: usize, d: i32) -> usize {
        match d {
            1 => {
                if v + 1 == n {
                    0
                } else {
                    v + 1
                }
            }
            -1 => {
                if v == 0 {
                    n - 1
                } else {
                    v - 1
                }
            }
            _ => v,
        }
    }

    /// Whether row y has links cut by a wall.
    #[inline(always)]
    fn is_wall_row(&self, y: usize) -> bool {
        self.walls.is_some() && (y == 0 || y + 1 == self.ny)
    }

    /// Column and row population `i` of node (x, y) streams from, or, when its link crosses
    /// a wall, `Err(wall)` with 0 for the bottom and 1 for the top wall.
    #[inline(always)]
    fn upstream(&self, x: usize, y: usize, i: usize) -> Result<(usize, usize), usize> {
        let (cx, cy) = (C[i][0], C[i][1]);
        let xs = Self::wrap(self.nx, x, -cx);
        if self.walls.is_some() {
            if cy == 1 && y == 0 {
                return Err(0);
            }
            if cy == -1 && y + 1 == self.ny {
                return Err(1);
            }
        }
        Ok((xs, Self::wrap(self.ny, y, -cy)))
    }

    /// Pre-collision deviations f - w rho0 of node (x, y): streamed from the post-collision
    /// `src`, bounced back at a wall with the moving-wall term (REFERENCE.md section 5),
    /// whose rho is the node's own (collision keeps it: rho0 plus the sum of its stored
    /// values). The rest parts w rho0 of a bounced pair are equal, so deviations bounce
    /// back like populations.
    #[inline(always)]
    fn gather(&self, src: &[f64], x: usize, y: usize) -> [f64; Q] {
        let mut f = [0.0; Q];
        if let (Some(u), true) = (self.walls, self.is_wall_row(y)) {
            let rho = self.rho0 + (0..Q).map(|i| src[self.at(y, i, x)]).sum::<f64>();
            for i in 0..Q {
                f[i] = match self.upstream(x, y, i) {
                    Ok((xs, ys)) => src[self.at(ys, i, xs)],
                    Err(w) => {
                        src[self.at(y, OPP[i], x)] + 6.0 * W[i] * rho * (C[i][0] as f64 * u[w])
                    }
                };
            }
        } else {
            for (i, fi) in f.iter_mut().enumerate() {
                let (xs, ys) = self.upstream(x, y, i).unwrap_or((x, y));
                *fi = src[self.at(ys, i, xs)];
            }
        }
        f
    }
}

/// `m` values of `src` from `start`.
#[inline(always)]
fn run(src: &[f64], start: usize, m: usize) -> &[f64] {
    &src[start..start + m]
}

/// Flow statistics of one row, gathered by the step from the populations it collided (the
/// velocity u = (j + F/2) / rho of each node, as the collision uses it): the largest |u|^2
/// (NaN if any node was NaN) and the sum of u_x along the row.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct RowStats {
    max_speed_sq: f64,
    sum_ux: f64,
}

impl RowStats {
    #[inline(always)]
    fn add(&mut self, ux: f64, uy: f64) {
        let u2 = ux * ux + uy * uy;
        // NaN sticks: `u2 > NaN` is false, and a NaN u2 replaces the maximum.
        if u2 > self.max_speed_sq || u2.is_nan() {
            self.max_speed_sq = u2;
        }
        self.sum_ux += ux;
    }

    /// [`RowStats::add`] for the nodes of a block, given u_x and |u|^2 of each: the same
    /// sum and the same maximum. The sum runs in node order; the maximum, which does not
    /// depend on the order (|u|^2 is never -0), in four independent lanes, so that no
    /// comparison waits on the one before; a NaN anywhere makes it NaN.
    #[inline(always)]
    fn add_block(&mut self, ux: &[f64], u2: &[f64]) {
        for v in ux {
            self.sum_ux += v;
        }
        let mut lanes = [self.max_speed_sq; 4];
        let mut nan = [false; 4];
        let chunks = u2.chunks_exact(4);
        let tail = chunks.remainder();
        for c in chunks {
            for l in 0..4 {
                lanes[l] = if c[l] > lanes[l] { c[l] } else { lanes[l] };
                nan[l] |= c[l].is_nan();
            }
        }
        for &v in tail {
            lanes[0] = if v > lanes[0] { v } else { lanes[0] };
            nan[0] |= v.is_nan();
        }
        if self.max_speed_sq.is_nan() || nan.iter().any(|n| *n) {
            self.max_speed_sq = f64::NAN;
        } else {
            self.max_speed_sq = lanes
                .into_iter()
                .fold(lanes[0], |a, b| if b > a { b } else { a });
        }
    }
}

/// Nodes a block of the statistics pass holds (two arrays of this many on the stack).
const STATS_BLOCK: usize = 64;

/// Stream and collide row `y` into `dst` (its nine sub-rows); returns the row's statistics.
///
/// Compiled twice on x86-64, for the build's target (SSE2: two doubles a vector) and for
/// AVX2 (four), and the copy the CPU can run is chosen at run time. The collision loop is
/// bound by arithmetic under SSE2 (docs/performance.md, "MRT D2Q9 lattice Boltzmann step").
/// Both copies do the same operations in the same order on every node, and Rust never fuses
/// `a * b + c`, so they give the same bits (`fused_step_matches_node_by_node` compares the
/// step with the one-node collision bit for bit).
#[multiversion::multiversion(targets("x86_64+avx2"))]
#[allow(clippy::too_many_arguments)]
fn step_row(
    geo: Geometry,
    fixed: FixedRates,
    src: &[f64],
    dst: &mut [f64],
    y: usize,
    nu: &[f64],
    fx: &[f64],
    fy: &[f64],
) -> RowStats {
    let nx = geo.nx;
    let store = |x: usize, p: &[f64; Q], dst: &mut [f64]| {
        for (i, v) in p.iter().enumerate() {
            dst[i * nx + x] = *v;
        }
    };
    let mut stats = RowStats::default();
    if geo.is_wall_row(y) || nx < 3 {
        for x in 0..nx {
            let f = geo.gather(src, x, y);
            let (p, ux, uy) = collide_with_velocity(&f, geo.rho0, nu[x], fx[x], fy[x], fixed);
            store(x, &p, dst);
            stats.add(ux, uy);
        }
        return stats;
    }
    // The two edge columns wrap in x; the others read shifted contiguous runs. The sum of
    // u_x runs over x = 0, nx - 1, then 1..nx - 1: a fixed order, so the same bits on any
    // number of threads.
    for x in [0, nx - 1] {
        let f = geo.gather(src, x, y);
        let (p, ux, uy) = collide_with_velocity(&f, geo.rho0, nu[x], fx[x], fy[x], fixed);
        store(x, &p, dst);
        stats.add(ux, uy);
    }
    let m = nx - 2;
    let ym = Geometry::wrap(geo.ny, y, -1);
    let yp = Geometry::wrap(geo.ny, y, 1);
    // Population i at x = k + 1 comes from row y - cy_i, column k + 1 - cx_i.
    let a0 = run(src, geo.at(y, 0, 1), m);
    let a1 = run(src, geo.at(y, 1, 0), m);
    let a2 = run(src, geo.at(ym, 2, 1), m);
    let a3 = run(src, geo.at(y, 3, 2), m);
    let a4 = run(src, geo.at(yp, 4, 1), m);
    let a5 = run(src, geo.at(ym, 5, 0), m);
    let a6 = run(src, geo.at(ym, 6, 2), m);
    let a7 = run(src, geo.at(yp, 7, 2), m);
    let a8 = run(src, geo.at(yp, 8, 0), m);
    let (nu, fx, fy) = (&nu[1..1 + m], &fx[1..1 + m], &fy[1..1 + m]);
    let mut sub = dst.chunks_exact_mut(nx);
    let d: [&mut [f64]; Q] = std::array::from_fn(|_| {
        let s = sub.next().expect("nine sub-rows");
        &mut s[1..1 + m]
    });
    for k in 0..m {
        let f = [
            a0[k], a1[k], a2[k], a3[k], a4[k], a5[k], a6[k], a7[k], a8[k],
        ];
        let p = collide(&f, geo.rho0, nu[k], fx[k], fy[k], fixed);
        for i in 0..Q {
            d[i][k] = p[i];
        }
    }
    // The statistics in a second pass over the row's populations, still in cache: folded
    // into the collision loop above (in-order sum, NaN-aware maximum), they cost the loop
    // its vectorisation and half its throughput. Keep the collision loop free of anything
    // carried from node to node, and re-run `cargo bench -p fluid-node --bench lbm_step`
    // after changing it (figures in docs/performance.md).
    // The pass itself goes by blocks: the velocities of a block first (node by node, a loop
    // that vectorises), then their in-order sum and their maximum ([`RowStats::add_block`]).
    let mut ux = [0.0; STATS_BLOCK];
    let mut u2 = [0.0; STATS_BLOCK];
    for start in (0..m).step_by(STATS_BLOCK) {
        let n = STATS_BLOCK.min(m - start);
        for j in 0..n {
            let k = start + j;
            let f = [
                a0[k], a1[k], a2[k], a3[k], a4[k], a5[k], a6[k], a7[k], a8[k],
            ];
            let (_, vx, vy) = macroscopic(&f, geo.rho0, fx[k], fy[k]);
            ux[j] = vx;
            u2[j] = vx * vx + vy * vy;
        }
        stats.add_block(&ux[..n], &u2[..n]);
    }
    stats
}

/// The MRT D2Q9 solver: two lattices of populations, the viscosity and force fields.
#[derive(Debug, Clone)]
pub struct MrtD2q9 {
    geo: Geometry,
    fixed: FixedRates,
    /// Post-collision populations of the last step, `[y][i][x]`.
    f: Vec<f64>,
    /// The lattice the next step writes.
    g: Vec<f64>,
    /// Kinematic viscosity per node, `[y][x]`.
    nu: Vec<f64>,
    /// Body force density per node, `[y][x]`.
    fx: Vec<f64>,
    fy: Vec<f64>,
    /// Per-row partial sums of the deterministic reductions.
    row_sums: Vec<f64>,
    /// Per-row flow statistics of the last step (zero before the first).
    row_stats: Vec<RowStats>,
    time: u64,
}

impl MrtD2q9 {
    /// Validate the configuration and allocate the lattices; the fluid starts at rest with
    /// the configured density and viscosity, no force.
    pub fn new(cfg: MrtConfig) -> Result<Self, String> {
        let MrtConfig {
            nx,
            ny,
            y_boundary,
            viscosity,
            density,
            fixed_rates,
        } = cfg;
        if nx < MIN_SIZE || ny < MIN_SIZE {
            return Err(format!(
                "lattice {nx} x {ny} is too small: at least {MIN_SIZE} nodes along x and y"
            ));
        }
        let nodes = nx
            .checked_mul(ny)
            .filter(|n| n.checked_mul(Q * std::mem::size_of::<f64>()).is_some())
            .ok_or_else(|| format!("lattice {nx} x {ny} is too large"))?;
        check_viscosity(viscosity)?;
        if !(density.is_finite() && density > 0.0) {
            return Err(format!("density {density} is not a finite positive number"));
        }
        for (name, s) in [("s_e", fixed_rates.s_e), ("s_eps", fixed_rates.s_eps)] {
            if !(s > 0.0 && s < 2.0) {
                return Err(format!("relaxation rate {name} = {s} is outside (0, 2)"));
            }
        }
        let walls = match y_boundary {
            YBoundary::Periodic => None,
            YBoundary::Walls { bottom, top } => {
                check_wall_speed("bottom", bottom)?;
                check_wall_speed("top", top)?;
                Some([bottom, top])
            }
        };
        let mut s = Self {
            geo: Geometry {
                nx,
                ny,
                walls,
                rho0: density,
            },
            fixed: fixed_rates,
            f: vec![0.0; nodes * Q],
            g: vec![0.0; nodes * Q],
            nu: vec![viscosity; nodes],
            fx: vec![0.0; nodes],
            fy: vec![0.0; nodes],
            row_sums: Vec::with_capacity(ny),
            row_stats: vec![RowStats::default(); ny],
            time: 0,
        };
        s.initialize_with(|_, _| (density, 0.0, 0.0))?;
        Ok(s)
    }

    pub fn nx(&self) -> usize {
        self.geo.nx
    }

    /// The populations after the last step (`[y][i][x]`) and the step count: with the
    /// viscosity and force fields, which the caller rebuilds, the lattice's whole state.
    pub fn saved_state(&self) -> (&[f64], u64) {
        (&self.f, self.time)
    }

    /// Replace the populations and the step count by ones from [`MrtD2q9::saved_state`] of
    /// a lattice of the same size.
    pub fn set_populations(&mut self, f: &[f64], time: u64) -> Result<(), String> {
        if f.len() != self.f.len() {
            return Err(format!(
                "{} populations given, the {} x {} lattice has {}",
                f.len(),
                self.geo.nx,
                self.geo.ny,
                self.f.len()
            ));
        }
        self.f.copy_from_slice(f);
        self.time = time;
        Ok(())
    }

    pub fn ny(&self) -> usize {
        self.geo.ny
    }

    /// Index of node (x, y) in the fields (`[y][x]`, x fastest).
    pub fn index(&self, x: usize, y: usize) -> usize {
        y * self.geo.nx + x
    }

    /// Steps taken since the last initialisation.
    pub fn time(&self) -> u64 {
        self.time
    }

    pub fn fixed_rates(&self) -> FixedRates {
        self.fixed
    }

    /// Bottom and top wall velocities, `None` when periodic in y.
    pub fn wall_velocities(&self) -> Option<[f64; 2]> {
        self.geo.walls
    }

    /// Change the wall velocities [bottom, top]; an error when periodic in y.
    pub fn set_wall_velocities(&mut self, u: [f64; 2]) -> Result<(), String> {
        if self.geo.walls.is_none() {
            return Err("the lattice is periodic in y: it has no walls".into());
        }
        check_wall_speed("bottom", u[0])?;
        check_wall_speed("top", u[1])?;
        self.geo.walls = Some(u);
        Ok(())
    }

    /// The kinematic viscosity field, `[y][x]`.
    pub fn viscosity(&self) -> &[f64] {
        &self.nu
    }

    /// Replace the viscosity field (`[y][x]`); nothing changes if any value is invalid
    /// (see [`check_viscosity`]).
    pub fn set_viscosity(&mut self, nu: &[f64]) -> Result<(), String> {
        self.check_len("viscosity", nu.len())?;
        for (k, &v) in nu.iter().enumerate() {
            check_viscosity(v)
                .map_err(|e| format!("node ({}, {}): {e}", k % self.geo.nx, k / self.geo.nx))?;
        }
        self.nu.copy_from_slice(nu);
        Ok(())
    }

    /// Viscosity from a solid fraction, nu = nu_f + (nu_s - nu_f) phi (S2023 eq. 1 divided by
    /// the reference density). Every phi must lie in [0, 1], so checking nu_f and nu_s
    /// checks every node.
    pub fn set_viscosity_from_fraction(
        &mut self,
        phi: &[f64],
        nu_f: f64,
        nu_s: f64,
    ) -> Result<(), String> {
        self.check_fraction_field(phi, nu_f, nu_s)?;
        if let Some(k) = phi.iter().position(|p| !(0.0..=1.0).contains(p)) {
            return Err(self.fraction_out_of_range(phi, k));
        }
        let min = min_len(self.geo.ny, self.geo.nx);
        self.nu
            .par_iter_mut()
            .zip(phi.par_iter())
            .with_min_len(min * self.geo.nx)
            .for_each(|(n, &p)| *n = nu_f + (nu_s - nu_f) * p);
        Ok(())
    }

    /// [`MrtD2q9::set_viscosity_from_fraction`] at the listed nodes only (`[y][x]` indices,
    /// repeats allowed); the rest of the field is left as it is.
    pub fn set_viscosity_from_fraction_at(
        &mut self,
        nodes: &[usize],
        phi: &[f64],
        nu_f: f64,
        nu_s: f64,
    ) -> Result<(), String> {
        self.check_fraction_field(phi, nu_f, nu_s)?;
        let n = self.nu.len();
        if let Some(&k) = nodes.iter().find(|&&k| k >= n) {
            return Err(format!(
                "node index {k} is outside the lattice of {n} nodes"
            ));
        }
        if let Some(&k) = nodes.iter().find(|&&k| !(0.0..=1.0).contains(&phi[k])) {
            return Err(self.fraction_out_of_range(phi, k));
        }
        for &k in nodes {
            self.nu[k] = nu_f + (nu_s - nu_f) * phi[k];
        }
        Ok(())
    }

    /// The length of a solid-fraction field and the two viscosities it mixes.
    fn check_fraction_field(&self, phi: &[f64], nu_f: f64, nu_s: f64) -> Result<(), String> {
        self.check_len("solid fraction", phi.len())?;
        check_viscosity(nu_f)?;
        check_viscosity(nu_s)
    }

    fn fraction_out_of_range(&self, phi: &[f64], k: usize) -> String {
        format!(
            "solid fraction {} at node ({}, {}) is outside [0, 1]",
            phi[k],
            k % self.geo.nx,
            k / self.geo.nx
        )
    }

    /// Same viscosity everywhere.
    pub fn set_uniform_viscosity(&mut self, nu: f64) -> Result<(), String> {
        check_viscosity(nu)?;
        self.nu.fill(nu);
        Ok(())
    }

    /// The body force density fields (fx, fy), `[y][x]`.
    pub fn force(&self) -> (&[f64], &[f64]) {
        (&self.fx, &self.fy)
    }

    /// Write access to the force fields (any finite values are valid).
    pub fn force_mut(&mut self) -> (&mut [f64], &mut [f64]) {
        (&mut self.fx, &mut self.fy)
    }

    /// Replace the force fields (`[y][x]`); nothing changes if a value is not finite.
    pub fn set_force(&mut self, fx: &[f64], fy: &[f64]) -> Result<(), String> {
        self.check_len("force x", fx.len())?;
        self.check_len("force y", fy.len())?;
        if let Some(k) = (0..fx.len()).find(|&k| !(fx[k].is_finite() && fy[k].is_finite())) {
            return Err(format!(
                "force ({}, {}) at node ({}, {}) is not finite",
                fx[k],
                fy[k],
                k % self.geo.nx,
                k / self.geo.nx
            ));
        }
        self.fx.copy_from_slice(fx);
        self.fy.copy_from_slice(fy);
        Ok(())
    }

    /// Same force density everywhere.
    pub fn set_uniform_force(&mut self, fx: f64, fy: f64) {
        self.fx.fill(fx);
        self.fy.fill(fy);
    }

    /// Reset the time to 0 and the populations to equilibrium with the given density and
    /// velocity per node (`[y][x]` slices); see [`MrtD2q9::initialize_with`].
    pub fn initialize(&mut self, rho: &[f64], ux: &[f64], uy: &[f64]) -> Result<(), String> {
        self.check_len("density", rho.len())?;
        self.check_len("velocity x", ux.len())?;
        self.check_len("velocity y", uy.len())?;
        let nx = self.geo.nx;
        self.initialize_with(|x, y| {
            let k = y * nx + x;
            (rho[k], ux[k], uy[k])
        })
    }

    /// Reset the time to 0 and the populations to equilibrium with `(rho, ux, uy) = f(x, y)`:
    /// afterwards [`MrtD2q9::velocity`] reports exactly these values under the current force
    /// (the populations carry the momentum rho u - F/2). Nothing changes on an error.
    pub fn initialize_with(
        &mut self,
        f: impl Fn(usize, usize) -> (f64, f64, f64),
    ) -> Result<(), String> {
        let geo = self.geo;
        let (nx, ny) = (geo.nx, geo.ny);
        for y in 0..ny {
            for x in 0..nx {
                let (rho, ux, uy) = f(x, y);
                if !(rho.is_finite() && rho > 0.0 && ux.is_finite() && uy.is_finite()) {
                    return Err(format!(
                        "initial state at node ({x}, {y}): density {rho} and velocity \
                         ({ux}, {uy}) must be finite, the density positive"
                    ));
                }
            }
        }
        let rest = kernel::rest_moments(geo.rho0);
        // Place each node's equilibrium where the next gather takes it from: the upstream
        // node's slot, or, across a wall, the node's own opposite slot less the wall term.
        // Every slot is written once (streaming is a permutation).
        for y in 0..ny {
            for x in 0..nx {
                let (rho, ux, uy) = f(x, y);
                let k = y * nx + x;
                let u0 = ux - 0.5 * self.fx[k] / rho;
                let u1 = uy - 0.5 * self.fy[k] / rho;
                let meq = kernel::equilibrium_moments(rho, u0, u1);
                let feq = kernel::populations(&std::array::from_fn(|j| meq[j] - rest[j]));
                for (i, &v) in feq.iter().enumerate() {
                    let slot = match geo.upstream(x, y, i) {
                        Ok((xs, ys)) => geo.at(ys, i, xs),
                        Err(_) => geo.at(y, OPP[i], x),
                    };
                    self.f[slot] = v;
                }
            }
        }
        // The wall terms of a sliding wall cancel in a node's sum (c_i . u_w = +-u_w for the
        // two diagonals), so the density the gather will use is the sum already stored.
        if let Some(u) = geo.walls {
            for y in [0, ny - 1] {
                for x in 0..nx {
                    let rho = geo.rho0 + (0..Q).map(|i| self.f[geo.at(y, i, x)]).sum::<f64>();
                    for i in 0..Q {
                        if let Err(w) = geo.upstream(x, y, i) {
                            self.f[geo.at(y, OPP[i], x)] -=
                                6.0 * W[i] * rho * (C[i][0] as f64 * u[w]);
                        }
                    }
                }
            }
        }
        self.time = 0;
        Ok(())
    }

    /// One time step: stream, bounce back at the walls, collide (fused, row-parallel).
    pub fn step(&mut self) {
        let geo = self.geo;
        let fixed = self.fixed;
        let nx = geo.nx;
        let src = &self.f[..];
        let (nu, fx, fy) = (&self.nu[..], &self.fx[..], &self.fy[..]);
        self.g
            .par_chunks_mut(Q * nx)
            .zip(self.row_stats.par_iter_mut())
            .enumerate()
            .with_min_len(min_len(geo.ny, nx))
            .for_each(|(y, (dst, stats))| {
                let r = y * nx..(y + 1) * nx;
                *stats = step_row(
                    geo,
                    fixed,
                    src,
                    dst,
                    y,
                    &nu[r.clone()],
                    &fx[r.clone()],
                    &fy[r],
                );
            });
        std::mem::swap(&mut self.f, &mut self.g);
        self.time += 1;
    }

    /// `n` steps.
    pub fn run(&mut self, n: u64) {
        for _ in 0..n {
            self.step();
        }
    }

    /// Pre-collision populations of node (x, y) at the current time.
    pub fn populations(&self, x: usize, y: usize) -> [f64; Q] {
        let d = self.geo.gather(&self.f, x, y);
        std::array::from_fn(|i| d[i] + W[i] * self.geo.rho0)
    }

    /// Density and velocity of node (x, y): rho u = sum f c + F/2.
    pub fn node(&self, x: usize, y: usize) -> (f64, f64, f64) {
        let k = self.index(x, y);
        let d = self.geo.gather(&self.f, x, y);
        macroscopic(&d, self.geo.rho0, self.fx[k], self.fy[k])
    }

    /// Density and velocity into caller buffers of nx * ny values (`[y][x]`).
    ///
    /// # Panics
    /// If a buffer has the wrong length.
    pub fn fields(&self, rho: &mut [f64], ux: &mut [f64], uy: &mut [f64]) {
        let (geo, nx) = (self.geo, self.geo.nx);
        for (name, len) in [("rho", rho.len()), ("ux", ux.len()), ("uy", uy.len())] {
            assert_eq!(len, self.nu.len(), "{name} buffer: wrong length");
        }
        let (src, fx, fy) = (&self.f[..], &self.fx[..], &self.fy[..]);
        rho.par_chunks_mut(nx)
            .zip(ux.par_chunks_mut(nx))
            .zip(uy.par_chunks_mut(nx))
            .enumerate()
            .with_min_len(min_len(geo.ny, nx))
            .for_each(|(y, ((r, a), b))| {
                for x in 0..nx {
                    let k = y * nx + x;
                    (r[x], a[x], b[x]) =
                        macroscopic(&geo.gather(src, x, y), geo.rho0, fx[k], fy[k]);
                }
            });
    }

    /// Density into a caller buffer of nx * ny values (`[y][x]`).
    ///
    /// # Panics
    /// If the buffer has the wrong length.
    pub fn density(&self, rho: &mut [f64]) {
        let (geo, nx) = (self.geo, self.geo.nx);
        assert_eq!(rho.len(), self.nu.len(), "rho buffer: wrong length");
        let src = &self.f[..];
        rho.par_chunks_mut(nx)
            .enumerate()
            .with_min_len(min_len(geo.ny, nx))
            .for_each(|(y, r)| {
                for (x, v) in r.iter_mut().enumerate() {
                    *v = geo.rho0 + geo.gather(src, x, y).iter().sum::<f64>();
                }
            });
    }

    /// Velocity into caller buffers of nx * ny values (`[y][x]`).
    ///
    /// # Panics
    /// If a buffer has the wrong length.
    pub fn velocity(&self, ux: &mut [f64], uy: &mut [f64]) {
        let (geo, nx) = (self.geo, self.geo.nx);
        assert_eq!(ux.len(), self.nu.len(), "ux buffer: wrong length");
        assert_eq!(uy.len(), self.nu.len(), "uy buffer: wrong length");
        let (src, fx, fy) = (&self.f[..], &self.fx[..], &self.fy[..]);
        ux.par_chunks_mut(nx)
            .zip(uy.par_chunks_mut(nx))
            .enumerate()
            .with_min_len(min_len(geo.ny, nx))
            .for_each(|(y, (a, b))| {
                for x in 0..nx {
                    let k = y * nx + x;
                    let (_, u, v) = macroscopic(&geo.gather(src, x, y), geo.rho0, fx[k], fy[k]);
                    (a[x], b[x]) = (u, v);
                }
            });
    }

    /// Total mass, the sum of the density: nx ny rho0 plus the sum of rho - rho0, taken per
    /// row and the rows added in order, so the result does not depend on the number of
    /// threads.
    pub fn total_mass(&mut self) -> f64 {
        let (geo, nx) = (self.geo, self.geo.nx);
        let src = &self.f[..];
        per_row(&mut self.row_sums, geo.ny, nx, |y| {
            (0..nx)
                .map(|x| geo.gather(src, x, y).iter().sum::<f64>())
                .fold(0.0, |a, b| a + b)
        });
        (nx * geo.ny) as f64 * geo.rho0 + ordered_sum(&self.row_sums)
    }

    /// Largest |u| over the lattice (NaN if any node is NaN; a maximum does not depend on
    /// the order of the reduction).
    pub fn max_speed(&self) -> f64 {
        let (geo, nx) = (self.geo, self.geo.nx);
        let (src, fx, fy) = (&self.f[..], &self.fx[..], &self.fy[..]);
        let nan_max = |a: f64, b: f64| {
            if a.is_nan() || b.is_nan() {
                f64::NAN
            } else {
                a.max(b)
            }
        };
        (0..geo.ny)
            .into_par_iter()
            .with_min_len(min_len(geo.ny, nx))
            .map(|y| {
                (0..nx)
                    .map(|x| {
                        let k = y * nx + x;
                        let (_, u, v) = macroscopic(&geo.gather(src, x, y), geo.rho0, fx[k], fy[k]);
                        (u * u + v * v).sqrt()
                    })
                    .fold(0.0, nan_max)
            })
            .reduce(|| 0.0, nan_max)
    }

    /// Largest |u| of the flow the last [`MrtD2q9::step`] collided (the state at the start
    /// of that step, u = (j + F/2) / rho), kept by the step itself: O(ny), no pass over the
    /// lattice. NaN if any node was NaN; 0 before the first step.
    pub fn last_step_max_speed(&self) -> f64 {
        let mut m: f64 = 0.0;
        for s in &self.row_stats {
            if s.max_speed_sq > m || s.max_speed_sq.is_nan() {
                m = s.max_speed_sq;
            }
        }
        m.sqrt()
    }

    /// [`MrtD2q9::last_step_max_speed`] over c_s = 1/sqrt(3).
    pub fn last_step_max_mach(&self) -> f64 {
        self.last_step_max_speed() * 3f64.sqrt()
    }

    /// Mean u_x along row y of the flow the last step collided (see
    /// [`MrtD2q9::last_step_max_speed`]).
    pub fn last_step_row_mean_ux(&self, y: usize) -> f64 {
        self.row_stats[y].sum_ux / self.geo.nx as f64
    }

    /// Largest Mach number, max |u| / c_s with c_s = 1/sqrt(3).
    pub fn max_mach(&self) -> f64 {
        self.max_speed() * 3f64.sqrt()
    }

    fn check_len(&self, what: &str, len: usize) -> Result<(), String> {
        if len != self.nu.len() {
            return Err(format!(
                "{what} field has {len} values, the {} x {} lattice {}",
                self.geo.nx,
                self.geo.ny,
                self.nu.len()
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn walls(nx: usize, ny: usize, nu: f64, u: [f64; 2]) -> MrtD2q9 {
        let b = YBoundary::Walls {
            bottom: u[0],
            top: u[1],
        };
        MrtD2q9::new(MrtConfig::new(nx, ny, b, nu)).unwrap()
    }

    /// The statistics the step keeps are those of the flow it collided: the same as a pass
    /// over the lattice before the step (largest speed, row means of u_x), to round-off;
    /// and a NaN anywhere shows in the maximum.
    #[test]
    fn step_keeps_the_statistics_of_the_flow_it_collided() {
        let (nx, ny) = (23, 17);
        let mut lat = walls(nx, ny, 0.1, [-0.02, 0.03]);
        let n = nx * ny;
        let fx: Vec<f64> = (0..n).map(|k| 1e-5 * ((k % 7) as f64 - 3.0)).collect();
        let fy: Vec<f64> = (0..n).map(|k| 2e-5 * ((k % 5) as f64 - 2.0)).collect();
        lat.set_force(&fx, &fy).unwrap();
        assert_eq!(lat.last_step_max_speed(), 0.0);
        lat.run(40);
        let (mut ux, mut uy) = (vec![0.0; n], vec![0.0; n]);
        lat.velocity(&mut ux, &mut uy);
        let before = lat.max_speed();
        lat.step();
        assert!((lat.last_step_max_speed() - before).abs() <= 1e-15 * before);
        assert!((lat.last_step_max_mach() - before * 3f64.sqrt()).abs() <= 1e-15);
        for y in 0..ny {
            let mean = ux[y * nx..(y + 1) * nx].iter().sum::<f64>() / nx as f64;
            assert!(
                (lat.last_step_row_mean_ux(y) - mean).abs() < 1e-16,
                "row {y}"
            );
        }
        lat.force_mut().0[5 * nx + 9] = f64::NAN;
        lat.step();
        assert!(lat.last_step_max_speed().is_nan());
    }

    /// A block of nodes adds to the statistics what they add one by one: the same bits of
    /// the sum and of the maximum for blocks of 0 to 13 nodes (whole groups of four and
    /// every remainder), and NaN wherever a NaN is (in the block or already in the row).
    #[test]
    fn a_block_adds_what_its_nodes_add_one_by_one() {
        let v = |k: usize, s: f64| ((k as f64 + s) * 0.731).sin() * 1e-2;
        for n in 0..=13usize {
            for nan_at in [None, Some(0), Some(n / 2), Some(n.saturating_sub(1))] {
                let ux: Vec<f64> = (0..n).map(|k| v(k, 0.0)).collect();
                let mut uy: Vec<f64> = (0..n).map(|k| v(k, 0.5)).collect();
                if let (Some(k), true) = (nan_at, n > 0) {
                    uy[k] = f64::NAN;
                }
                let u2: Vec<f64> = ux.iter().zip(&uy).map(|(x, y)| x * x + y * y).collect();
                for start in [
                    RowStats::default(),
                    RowStats {
                        max_speed_sq: 3e-5,
                        sum_ux: 0.25,
                    },
                ] {
                    let (mut one, mut block) = (start, start);
                    for k in 0..n {
                        one.add(ux[k], uy[k]);
                    }
                    block.add_block(&ux, &u2);
                    assert_eq!(one.sum_ux.to_bits(), block.sum_ux.to_bits(), "n {n}");
                    assert_eq!(
                        one.max_speed_sq.is_nan(),
                        block.max_speed_sq.is_nan(),
                        "n {n}"
                    );
                    if !one.max_speed_sq.is_nan() {
                        assert_eq!(one.max_speed_sq.to_bits(), block.max_speed_sq.to_bits());
                    }
                }
            }
        }
        let mut row = RowStats {
            max_speed_sq: f64::NAN,
            sum_ux: 0.0,
        };
        row.add_block(&[0.1], &[0.01]);
        assert!(row.max_speed_sq.is_nan());
    }

    /// Bad configurations are errors, not panics.
    #[test]
    fn bad_configurations_are_errors() {
        let p = YBoundary::Periodic;
        for (cfg, what) in [
            (MrtConfig::new(1, 8, p, 0.1), "too small"),
            (MrtConfig::new(8, 1, p, 0.1), "too small"),
            (MrtConfig::new(8, 8, p, 0.0), "positive"),
            (MrtConfig::new(8, 8, p, -0.1), "positive"),
            (MrtConfig::new(8, 8, p, f64::NAN), "positive"),
            (MrtConfig::new(8, 8, p, 1e-18), "s_nu"),
            (MrtConfig::new(8, 8, p, 1e300), "s_q"),
            (
                MrtConfig::new(
                    8,
                    8,
                    YBoundary::Walls {
                        bottom: 0.0,
                        top: 0.6,
                    },
                    0.1,
                ),
                "sound speed",
            ),
            (
                MrtConfig {
                    fixed_rates: FixedRates {
                        s_e: 2.0,
                        s_eps: 1.0,
                    },
                    ..MrtConfig::new(8, 8, p, 0.1)
                },
                "s_e",
            ),
            (
                MrtConfig {
                    density: 0.0,
                    ..MrtConfig::new(8, 8, p, 0.1)
                },
                "density",
            ),
            (MrtConfig::new(usize::MAX / 2, 4, p, 0.1), "too large"),
        ] {
            let e = MrtD2q9::new(cfg).unwrap_err();
            assert!(e.contains(what), "{e:?} should mention {what:?}");
        }
        let mut s = walls(4, 4, 0.1, [0.0, 0.0]);
        assert!(s.set_viscosity(&[0.1; 15]).is_err());
        let mut nu = vec![0.1; 16];
        nu[5] = -1.0;
        let e = s.set_viscosity(&nu).unwrap_err();
        assert!(e.contains("node (1, 1)"), "{e}");
        assert_eq!(s.viscosity()[5], 0.1, "unchanged after an error");
        assert!(s.set_viscosity_from_fraction(&[1.5; 16], 0.1, 1.0).is_err());
        let mut fx = vec![0.0; 16];
        fx[3] = f64::INFINITY;
        assert!(s.set_force(&fx, &[0.0; 16]).is_err());
        assert!(s.initialize_with(|_, _| (-1.0, 0.0, 0.0)).is_err());
        let mut q = MrtD2q9::new(MrtConfig::new(4, 4, p, 0.1)).unwrap();
        assert!(q.set_wall_velocities([0.0, 0.1]).is_err());
    }

    /// Initialisation is the inverse of the gather: the reported fields are the requested
    /// ones, walls and force included.
    #[test]
    fn initial_fields_are_reported_back() {
        let (nx, ny) = (5, 6);
        let mut s = walls(nx, ny, 0.1, [-0.03, 0.05]);
        let (fx, fy): (Vec<f64>, Vec<f64>) = (0..nx * ny)
            .map(|k| (1e-4 * (k as f64).sin(), 2e-4 * (k as f64).cos()))
            .unzip();
        s.set_force(&fx, &fy).unwrap();
        let init = |x: usize, y: usize| {
            (
                1.0 + 0.01 * (x as f64 - y as f64),
                0.02 * (x + y) as f64 / 10.0,
                -0.01 * x as f64 / 5.0,
            )
        };
        s.initialize_with(init).unwrap();
        for y in 0..ny {
            for x in 0..nx {
                let (r, u, v) = s.node(x, y);
                let (r0, u0, v0) = init(x, y);
                assert!((r - r0).abs() < 1e-14 && (u - u0).abs() < 1e-14 && (v - v0).abs() < 1e-14);
            }
        }
    }

    /// The vectorised interior path and the generic gather agree: a step equals collisions
    /// of the gathered populations node by node, bit for bit. Rows of 37 nodes run the
    /// vector loop several times over, in whichever copy of the step the CPU takes (SSE2 or
    /// AVX2), besides its remainder.
    #[test]
    fn fused_step_matches_node_by_node() {
        for (boundary, (nx, ny)) in [
            (YBoundary::Periodic, (7, 5)),
            (
                YBoundary::Walls {
                    bottom: 0.02,
                    top: -0.01,
                },
                (7, 5),
            ),
            (
                YBoundary::Walls {
                    bottom: 0.02,
                    top: -0.01,
                },
                (37, 6),
            ),
        ] {
            let mut s = MrtD2q9::new(MrtConfig::new(nx, ny, boundary, 0.2)).unwrap();
            let nu: Vec<f64> = (0..nx * ny).map(|k| 0.05 + 0.01 * k as f64).collect();
            s.set_viscosity(&nu).unwrap();
            s.set_uniform_force(1e-4, -2e-4);
            s.initialize_with(|x, y| (1.0 + 0.01 * x as f64, 0.01 * y as f64, 0.003))
                .unwrap();
            s.run(3);
            let before = s.clone();
            s.step();
            for y in 0..ny {
                for x in 0..nx {
                    let k = s.index(x, y);
                    let post = collide(
                        &before.geo.gather(&before.f, x, y),
                        1.0,
                        nu[k],
                        1e-4,
                        -2e-4,
                        FixedRates::default(),
                    );
                    for (i, p) in post.iter().enumerate() {
                        assert_eq!(s.f[s.geo.at(y, i, x)], *p, "({x}, {y}) i = {i}");
                    }
                }
            }
        }
    }

    /// Steps give the same bits whatever the number of threads.
    #[test]
    fn results_do_not_depend_on_threads() {
        let make = || {
            let mut s = walls(64, 300, 0.1, [0.01, -0.01]);
            s.set_uniform_force(1e-5, 0.0);
            s
        };
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let mut s = make();
                s.run(20);
                (s.f.clone(), s.total_mass())
            })
        };
        assert_eq!(run(1), run(3));
    }
}
