//! Periodic pseudo-spectral incompressible Navier–Stokes solver, 2D and 3D.
//!
//! One step of L2020 eq. 34 without the capillary terms (single fluid):
//!
//! ```text
//! û* = P [ E (ûⁿ + Δt (N̂ⁿ + f̂/ρ)) ],   E = exp(-ν k² Δt),   N = -∇·(u u)
//! ```
//!
//! - the viscous term is integrated exactly by the integrating factor `E` (no viscous time-step
//!   limit; a Stokes mode decays exactly as `exp(-ν k² t)`);
//! - advection is explicit (Euler), in divergence form so that the mean momentum is untouched
//!   to round-off, with the 2/3 rule applied to `N̂`;
//! - `P = I - k kᵀ / k²` projects onto divergence-free fields (the intermediate pressure `p*`);
//! - the body force `f` (a force density) acts on the mean mode only;
//! - a binary fluid adds the capillary force density `f_c = -ψ∇μ_ψ - φ∇μ_φ` of L2020 eq. 34
//!   (loaded by [`SpectralNs::set_force_density`] before each step, on every mode: it is
//!   already a pseudo-spectral product, not dealiased, as in the Cahn–Hilliard step); a single
//!   fluid never allocates or touches it.
//!
//! The penalty of L2020 eqs. 37–38 is added by [`SpectralNs::add_projected`]: `ûⁿ⁺¹ = û* + P f̂`.
//!
//! The spectral velocity `û` is the state; between steps the real velocity is the inverse
//! transform of `û` (a deterministic function of it), so saving `û` saves everything. Within
//! an SPM step, [`SpectralNs::advance_intermediate_on`] may leave rows behind, which the
//! solver remembers and [`SpectralNs::add_projected`] rebuilds.
use crate::grid::{Grid, Wavenumbers};
use crate::parallel::{for_each_row, ordered_sum, per_row};
use crate::transform::{Modes, Transform};
use rustfft::num_complex::Complex64;

/// The flow solver: fields, plans and scratch for one grid.
pub struct SpectralNs {
    grid: Grid,
    waves: Wavenumbers,
    transform: Transform,
    nu: f64,
    dt: f64,
    /// Body force density over density, per component.
    body_accel: [f64; 3],
    /// `exp(-ν k_a² Δt)` per axis: `E` is their product.
    decay: [Vec<f64>; 3],
    /// Real velocity components (the inverse transform of `u_hat`, except on `stale` rows).
    u: Vec<Vec<f64>>,
    /// Rows (`z * ny + y`) of `u` that still hold uⁿ after [`SpectralNs::advance_intermediate_on`]
    /// until [`SpectralNs::add_projected`] rebuilds them.
    stale: Vec<bool>,
    /// Scratch flags: the stale rows a penalty reads.
    missing: Vec<bool>,
    /// Spectral velocity components (the state).
    u_hat: Vec<Vec<Complex64>>,
    /// Advection term (3D) or the transformed products `u_a u_b` it is formed from (2D, in
    /// the order of [`PAIRS_2D`]), then the transformed penalty force.
    nl_hat: Vec<Vec<Complex64>>,
    /// Stored kx that the 2/3 rule keeps (a prefix).
    kept_kx: usize,
    tmp_hat: Vec<Complex64>,
    scratch: Vec<f64>,
    partials: Vec<f64>,
    /// Per-row pairs (energy and largest squared speed) of [`SpectralNs::energy_and_max_speed`].
    row_pairs: Vec<(f64, f64)>,
    /// Transformed force density over density `f̂/ρ` per component (binary fluids only;
    /// empty until [`SpectralNs::enable_force_density`]).
    force_hat: Vec<Vec<Complex64>>,
}

/// Up to three components as slices (empty beyond `v.len()`): pass `&mut out[..d]`.
fn slices<T>(v: &mut [Vec<T>]) -> [&mut [T]; 3] {
    let mut it = v.iter_mut();
    std::array::from_fn(|_| it.next().map_or(&mut [][..], |x| &mut x[..]))
}

impl SpectralNs {
    /// A fluid at rest on `grid` with kinematic viscosity `nu`, time step `dt` and body force
    /// density over density `body_accel` (z ignored in 2D). Allocates every buffer and plan.
    pub fn new(grid: Grid, nu: f64, dt: f64, body_accel: [f64; 3]) -> Self {
        let waves = Wavenumbers::new(grid);
        let decay = [&waves.x, &waves.y, &waves.z].map(|a| {
            a.k2.iter()
                .map(|k2| (-nu * k2 * dt).exp())
                .collect::<Vec<f64>>()
        });
        let d = grid.dims;
        let kept_kx = waves.x.keep.iter().take_while(|&&k| k).count();
        debug_assert!(waves.x.keep[kept_kx..].iter().all(|&k| !k));
        let mut body = body_accel;
        if d == 2 {
            body[2] = 0.0;
        }
        Self {
            grid,
            waves,
            // 2D: the two components' inverse transforms share their parallel passes (one
            // more spectrum); in 3D a transform is long enough that a pass more costs nothing.
            transform: Transform::with_batch(grid, 0, if d == 2 { 2 } else { 1 }),
            nu,
            dt,
            body_accel: body,
            decay,
            u: vec![vec![0.0; grid.cells()]; d],
            stale: vec![false; grid.rows()],
            missing: vec![false; grid.rows()],
            u_hat: vec![vec![Complex64::default(); grid.modes()]; d],
            nl_hat: vec![vec![Complex64::default(); grid.modes()]; if d == 2 { 3 } else { d }],
            kept_kx,
            tmp_hat: vec![Complex64::default(); grid.modes()],
            scratch: vec![0.0; grid.cells()],
            partials: Vec::with_capacity(grid.rows()),
            row_pairs: Vec::with_capacity(grid.rows()),
            force_hat: Vec::new(),
        }
    }

    /// Allocate the force-density buffers (zero force) so that
    /// [`SpectralNs::set_force_density`] allocates nothing; from now on every
    /// [`SpectralNs::advance_intermediate`] adds the loaded force.
    pub fn enable_force_density(&mut self) {
        let g = self.grid;
        self.force_hat = vec![vec![Complex64::default(); g.modes()]; g.dims];
    }

    /// Load a force density `f` (mass / (length² time²), one real field per component, at
    /// least `dims`) for the next [`SpectralNs::advance_intermediate`]: it adds `Δt f̂ / ρ`
    /// before the viscous factor and the projection (L2020 eq. 34's capillary terms). Needs
    /// [`SpectralNs::enable_force_density`] first (otherwise an error).
    pub fn set_force_density(&mut self, f: &[Vec<f64>], rho: f64) -> Result<(), String> {
        let d = self.grid.dims;
        if self.force_hat.len() != d || f.len() < d {
            return Err(format!(
                "spectral-ns: a force density needs enable_force_density and {d} components \
                 (got {})",
                f.len()
            ));
        }
        let inv_rho = 1.0 / rho;
        for (c, fc) in f.iter().enumerate().take(d) {
            if fc.len() != self.grid.cells() {
                return Err(format!(
                    "spectral-ns: force component {c} has {} values, the grid {}",
                    fc.len(),
                    self.grid.cells()
                ));
            }
        }
        let nx = self.grid.nx;
        let mut specs = slices(&mut self.force_hat);
        self.transform.forward_rows(
            &mut specs[..d],
            |c, r, out| out.copy_from_slice(&f[c][r * nx..(r + 1) * nx]),
            Modes::All,
        );
        for_each_row(&mut specs[..d], self.grid.nxh(), |_, rows| {
            for row in rows.iter_mut() {
                for v in row.iter_mut() {
                    *v *= inv_rho;
                }
            }
        });
        Ok(())
    }

    pub fn grid(&self) -> Grid {
        self.grid
    }

    pub fn viscosity(&self) -> f64 {
        self.nu
    }

    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// Real velocity component `c` (x fastest, see [`Grid::index`]). Between
    /// [`Self::advance_intermediate_on`] and [`Self::add_projected`] only the rows it updated
    /// hold u*; the others still hold uⁿ.
    pub fn velocity(&self, c: usize) -> &[f64] {
        &self.u[c]
    }

    /// All real velocity components (see [`Self::velocity`] for the rows that lag).
    pub fn velocity_components(&self) -> &[Vec<f64>] {
        &self.u
    }

    /// Spectral velocity component `c`.
    pub fn spectrum(&self, c: usize) -> &[Complex64] {
        &self.u_hat[c]
    }

    /// Set the velocity to `f(x, y, z)` at every node, projected onto divergence-free fields.
    pub fn set_velocity(&mut self, f: impl Fn(usize, usize, usize) -> [f64; 3]) {
        let g = self.grid;
        for c in 0..g.dims {
            for z in 0..g.nz {
                for y in 0..g.ny {
                    for x in 0..g.nx {
                        self.scratch[g.index(x, y, z)] = f(x, y, z)[c];
                    }
                }
            }
            self.transform.forward(&self.scratch, &mut self.u_hat[c]);
        }
        self.project_state();
        self.sync_real();
    }

    /// Replace the spectral state by `spectrum` (component-major, as [`Self::spectrum`]
    /// gives it) and rebuild the real field from it.
    pub fn set_spectrum(&mut self, spectrum: &[Vec<Complex64>]) {
        for (dst, src) in self.u_hat.iter_mut().zip(spectrum) {
            dst.copy_from_slice(src);
        }
        self.sync_real();
    }

    /// Real field := inverse transform of the spectral state.
    fn sync_real(&mut self) {
        Self::sync_rows(&mut self.transform, &self.u_hat, &mut self.u, &[]);
        self.stale.fill(false);
    }

    /// Real field := inverse transform of the spectral state, on the rows flagged in `rows`
    /// only (empty: all).
    fn sync_rows(
        transform: &mut Transform,
        u_hat: &[Vec<Complex64>],
        u: &mut [Vec<f64>],
        rows: &[bool],
    ) {
        let d = u.len();
        let specs: [&[Complex64]; 3] = std::array::from_fn(|c| match u_hat.get(c) {
            Some(h) => &h[..],
            None => &[],
        });
        let mut reals = slices(u);
        transform.inverse_rows(&specs[..d], &mut reals[..d], rows);
    }

    fn project_state(&mut self) {
        match self.grid.dims {
            2 => self.project_modes::<2>(),
            _ => self.project_modes::<3>(),
        }
    }

    /// [`Self::project_state`] for `D` components.
    fn project_modes<const D: usize>(&mut self) {
        let g = self.grid;
        let w = &self.waves;
        let nxh = g.nxh();
        let kx = &w.x.k[..nxh];
        let mut fields = slices(&mut self.u_hat);
        for_each_row(&mut fields[..D], nxh, |r, rows| {
            let rows = components::<D>(rows);
            let (iy, iz) = g.row_yz(r);
            let kyz = [w.y.k[iy], w.z.k[iz]];
            for ix in 0..nxh {
                let k = wavevector::<D>(kx[ix], kyz);
                let mut v: [Complex64; D] = std::array::from_fn(|c| rows[c][ix]);
                project(&k, &mut v);
                for c in 0..D {
                    rows[c][ix] = v[c];
                }
            }
        });
    }

    /// The transformed products `P̂_ab = (u_a u_b)^` the advection term `N̂_a = -i k_b P̂_ab`
    /// is formed from, each finished only on the modes the 2/3 rule keeps ([`Modes::Band`]).
    /// 2D: the three products go to `nl_hat` in one batch, and [`Self::advance_intermediate`]
    /// forms `N̂` from them. 3D: one product at a time (no room for six spectra at the grid
    /// sizes 3D runs at), each added to `N̂` in `nl_hat`.
    fn advection(&mut self) {
        let g = self.grid;
        let d = g.dims;
        let nx = g.nx;
        let band = Modes::Band {
            kx: self.kept_kx,
            ky: &self.waves.y.keep,
        };
        let u = &self.u;
        // Row r of u_a u_b.
        let product = |(a, b): (usize, usize), r: usize, out: &mut [f64]| {
            let (ua, ub) = (&u[a][r * nx..(r + 1) * nx], &u[b][r * nx..(r + 1) * nx]);
            for ((o, x), y) in out.iter_mut().zip(ua).zip(ub) {
                *o = x * y;
            }
        };
        if d == 2 {
            let mut specs = slices(&mut self.nl_hat);
            self.transform
                .forward_rows(&mut specs, |f, r, out| product(PAIRS_2D[f], r, out), band);
            return;
        }
        // The first product each N_c appears in, (0, c), writes it instead of adding to it:
        // no pass zeroes the three spectra first.
        for a in 0..d {
            for b in a..d {
                self.transform.forward_rows(
                    &mut [&mut self.tmp_hat[..]],
                    |_, r, out| product((a, b), r, out),
                    band,
                );
                let (waves, p_hat, nl) = (&self.waves, &self.tmp_hat[..], &mut self.nl_hat[..]);
                match (a, b) {
                    (0, 0) => Self::add_advection_term::<0, 0>(g, waves, p_hat, nl),
                    (0, 1) => Self::add_advection_term::<0, 1>(g, waves, p_hat, nl),
                    (0, 2) => Self::add_advection_term::<0, 2>(g, waves, p_hat, nl),
                    (1, 1) => Self::add_advection_term::<1, 1>(g, waves, p_hat, nl),
                    (1, 2) => Self::add_advection_term::<1, 2>(g, waves, p_hat, nl),
                    _ => Self::add_advection_term::<2, 2>(g, waves, p_hat, nl),
                }
            }
        }
    }

    /// 3D: the transformed product `P̂ = (u_A u_B)^` in `tmp_hat` into `N̂` in `nl_hat`:
    /// `N̂_A -= i k_B P̂` and, for A != B, `N̂_B -= i k_A P̂`; the first product each `N̂_c`
    /// appears in, (0, c), writes it. One function per pair, so that the loop over modes has
    /// no branch on the pair. Modes outside the band get unfinished values, which the step
    /// never reads.
    fn add_advection_term<const A: usize, const B: usize>(
        g: Grid,
        w: &Wavenumbers,
        p_hat: &[Complex64],
        nl_hat: &mut [Vec<Complex64>],
    ) {
        let nxh = g.nxh();
        let kx = &w.x.k[..nxh];
        let (lo, hi) = nl_hat.split_at_mut(B);
        let nb: &mut [Complex64] = &mut hi[0][..];
        // fields[0] = N̂_A, fields[1] = N̂_B when A != B.
        let mut pair: [&mut [Complex64]; 2] = if A == B {
            [nb, &mut []]
        } else {
            [&mut lo[A][..], nb]
        };
        let fields = if A == B {
            &mut pair[..1]
        } else {
            &mut pair[..]
        };
        for_each_row(fields, nxh, |r, rows| {
            let (iy, iz) = g.row_yz(r);
            let p = &p_hat[r * nxh..(r + 1) * nxh];
            let axis = |axis: usize, ix: usize| match axis {
                0 => kx[ix],
                1 => w.y.k[iy],
                _ => w.z.k[iz],
            };
            let (first, rest) = rows.split_at_mut(1);
            let na = &mut first[0][..nxh];
            if A == B {
                for ix in 0..nxh {
                    let n = minus_i_k(axis(B, ix), p[ix]);
                    if A == 0 {
                        na[ix] = n;
                    } else {
                        na[ix] += n;
                    }
                }
                return;
            }
            let nb = &mut rest[0][..nxh];
            for ix in 0..nxh {
                let n = minus_i_k(axis(B, ix), p[ix]);
                na[ix] += n;
                let n = minus_i_k(axis(A, ix), p[ix]);
                if A == 0 {
                    nb[ix] = n;
                } else {
                    nb[ix] += n;
                }
            }
        });
    }

    /// uⁿ → u* (L2020 eq. 34 without capillarity): advection, body force, exact viscous
    /// decay, projection; the real field is updated to u*.
    pub fn advance_intermediate(&mut self) {
        self.advance_intermediate_on(&[]);
    }

    /// [`Self::advance_intermediate`] that updates the real field only on the grid rows
    /// flagged in `rows` (`z * ny + y`; empty: all). The other rows keep uⁿ, and the solver
    /// remembers them: [`Self::add_projected`] brings those it reads up to date first, then
    /// rebuilds the whole real field. For a step whose penalty follows and which reads u*
    /// only where there are solids (the impulses and the penalty of L2020 eqs. 35-38).
    pub fn advance_intermediate_on(&mut self, rows: &[bool]) {
        self.advection();
        match self.grid.dims {
            2 => self.advance_modes::<2>(),
            _ => self.advance_modes::<3>(),
        }
        Self::sync_rows(&mut self.transform, &self.u_hat, &mut self.u, rows);
        for (r, s) in self.stale.iter_mut().enumerate() {
            *s = !rows.get(r).copied().unwrap_or(true);
        }
    }

    /// The spectral part of [`Self::advance_intermediate_on`] for `D` components: the loop
    /// over modes, compiled once per dimension so that the component loops unroll and each
    /// row's slices are taken once.
    fn advance_modes<const D: usize>(&mut self) {
        let g = self.grid;
        let dt = self.dt;
        let w = &self.waves;
        let decay = &self.decay;
        let nl = &self.nl_hat;
        let force = &self.force_hat;
        let forced = !force.is_empty();
        let nxh = g.nxh();
        let mean_kick: [f64; D] =
            std::array::from_fn(|c| dt * self.body_accel[c] * g.cells() as f64);
        let (kx, keep_x, decay_x) = (&w.x.k[..nxh], &w.x.keep[..nxh], &decay[0][..nxh]);
        let mut fields = slices(&mut self.u_hat);
        for_each_row(&mut fields[..D], nxh, |r, rows| {
            let rows = components::<D>(rows);
            let (iy, iz) = g.row_yz(r);
            let eyz = decay[1][iy] * decay[2][iz];
            let keep_yz = w.y.keep[iy] && w.z.keep[iz];
            let kyz = [w.y.k[iy], w.z.k[iz]];
            let span = r * nxh..(r + 1) * nxh;
            // Row r of what N̂ is formed from: the three products (2D) or N̂ itself (3D).
            let nl: [&[Complex64]; 3] = std::array::from_fn(|j| &nl[j][span.clone()]);
            let force: [&[Complex64]; D] = std::array::from_fn(|c| match force.get(c) {
                Some(f) => &f[span.clone()],
                None => &[],
            });
            for ix in 0..nxh {
                let e = decay_x[ix] * eyz;
                let keep = keep_yz && keep_x[ix];
                let k = wavevector::<D>(kx[ix], kyz);
                let mut v = [Complex64::default(); D];
                for c in 0..D {
                    let mut s = rows[c][ix];
                    if keep {
                        let n = if D == 2 {
                            // N̂_c = -i k_x P̂_cx - i k_y P̂_cy, summed as the 3D path does.
                            let mut n = Complex64::default();
                            n += minus_i_k(k[0], nl[PAIR_2D[c][0]][ix]);
                            n += minus_i_k(k[1], nl[PAIR_2D[c][1]][ix]);
                            n
                        } else {
                            nl[c][ix]
                        };
                        s += n * dt;
                    }
                    if r == 0 && ix == 0 {
                        s.re += mean_kick[c];
                    }
                    if forced {
                        s += force[c][ix] * dt;
                    }
                    v[c] = s * e;
                }
                project(&k, &mut v);
                for c in 0..D {
                    rows[c][ix] = v[c];
                }
            }
        });
    }

    /// `û += P f̂` with `f` given component by component in real space (L2020 eqs. 37–38:
    /// the penalty `φ (u_p - u*)` and the pressure p** that keeps u divergence-free); the
    /// real field is updated.
    ///
    /// `force(c, r, u_c, out)` writes row `r` of component `c` of the force into `out` (every
    /// element), given row `r` of the real velocity component `u_c`; it may read `u_c` only
    /// on the rows flagged in `reads` (empty: all), which are brought up to date first if
    /// [`Self::advance_intermediate_on`] left them behind (a sub-cycled fibre corrects its
    /// positions after the impulses, so its penalty can reach a row the impulses did not).
    /// Rows are formed as the transform takes them, all components in one batch, so `f` is
    /// never stored.
    pub fn add_projected(
        &mut self,
        reads: &[bool],
        force: impl Fn(usize, usize, &[f64], &mut [f64]) + Sync,
    ) {
        let mut missing = false;
        for (r, m) in self.missing.iter_mut().enumerate() {
            *m = self.stale[r] && reads.get(r).copied().unwrap_or(true);
            missing |= *m;
        }
        if missing {
            Self::sync_rows(&mut self.transform, &self.u_hat, &mut self.u, &self.missing);
        }
        let g = self.grid;
        let d = g.dims;
        let nx = g.nx;
        let u = &self.u;
        let mut specs = slices(&mut self.nl_hat);
        self.transform.forward_rows(
            &mut specs[..d],
            |c, r, out| force(c, r, &u[c][r * nx..(r + 1) * nx], out),
            Modes::All,
        );
        match d {
            2 => self.add_projected_modes::<2>(),
            _ => self.add_projected_modes::<3>(),
        }
        self.sync_real();
    }

    /// `û += P f̂` on the modes, `f̂` in `nl_hat`, for `D` components.
    fn add_projected_modes<const D: usize>(&mut self) {
        let g = self.grid;
        let w = &self.waves;
        let f_hat = &self.nl_hat;
        let nxh = g.nxh();
        let kx = &w.x.k[..nxh];
        let mut fields = slices(&mut self.u_hat);
        for_each_row(&mut fields[..D], nxh, |r, rows| {
            let rows = components::<D>(rows);
            let (iy, iz) = g.row_yz(r);
            let kyz = [w.y.k[iy], w.z.k[iz]];
            let span = r * nxh..(r + 1) * nxh;
            let f: [&[Complex64]; D] = std::array::from_fn(|c| &f_hat[c][span.clone()]);
            for ix in 0..nxh {
                let k = wavevector::<D>(kx[ix], kyz);
                let mut v: [Complex64; D] = std::array::from_fn(|c| f[c][ix]);
                project(&k, &mut v);
                for c in 0..D {
                    rows[c][ix] += v[c];
                }
            }
        });
    }

    /// Kinetic energy `ρ/2 Σ |u|²` over all cells (cell volume 1).
    pub fn kinetic_energy(&mut self, rho: f64) -> f64 {
        self.energy_and_max_speed(rho).0
    }

    /// Largest speed `|u|` over all nodes.
    pub fn max_speed(&mut self) -> f64 {
        self.energy_and_max_speed(1.0).1
    }

    /// [`SpectralNs::kinetic_energy`] and [`SpectralNs::max_speed`] in one pass over the
    /// field, rows in parallel, each summed in interleaved lanes (`row_energy_and_max`):
    /// a fixed order whatever the threads. One running sum would wait on each addition in
    /// turn (latency-bound: 3x slower at 256 x 200). NaN anywhere makes both NaN, so that a
    /// broken field is seen.
    pub fn energy_and_max_speed(&mut self, rho: f64) -> (f64, f64) {
        let g = self.grid;
        let u = &self.u;
        per_row(&mut self.row_pairs, g.rows(), g.nx, |r| {
            let row = r * g.nx..(r + 1) * g.nx;
            match u.len() {
                2 => row_energy_and_max([&u[0][row.clone()], &u[1][row]]),
                3 => row_energy_and_max([&u[0][row.clone()], &u[1][row.clone()], &u[2][row]]),
                d => unreachable!("a velocity field of {d} components"),
            }
        });
        let energy = self.row_pairs.iter().fold(0.0, |a, (e, _)| a + e);
        let max2 = self.row_pairs.iter().fold(0.0f64, |a, &(e, b)| {
            if e.is_nan() || a.is_nan() {
                f64::NAN
            } else {
                a.max(b)
            }
        });
        (0.5 * rho * energy, max2.sqrt())
    }

    /// Mean velocity over the box (the mean mode).
    pub fn mean_velocity(&self) -> [f64; 3] {
        let n = self.grid.cells() as f64;
        std::array::from_fn(|c| self.u_hat.get(c).map_or(0.0, |h| h[0].re / n))
    }

    /// Largest |∇·u| over the nodes, with the spectral derivative the projection uses.
    pub fn max_divergence(&mut self) -> f64 {
        let g = self.grid;
        let w = &self.waves;
        let nxh = g.nxh();
        let uh = &self.u_hat;
        let mut fields = [&mut self.tmp_hat[..]];
        for_each_row(&mut fields, nxh, |r, rows| {
            let (iy, iz) = g.row_yz(r);
            for ix in 0..nxh {
                let k = [w.x.k[ix], w.y.k[iy], w.z.k[iz]];
                let mut s = Complex64::default();
                for (c, comp) in uh.iter().enumerate() {
                    let v = comp[r * nxh + ix];
                    s += Complex64::new(-k[c] * v.im, k[c] * v.re);
                }
                rows[0][ix] = s;
            }
        });
        self.transform.inverse(&self.tmp_hat, &mut self.scratch);
        let s = &self.scratch;
        per_row(&mut self.partials, g.rows(), g.nx, |r| {
            s[r * g.nx..(r + 1) * g.nx]
                .iter()
                .fold(0.0f64, |m, v| m.max(v.abs()))
        });
        self.partials.iter().fold(0.0f64, |a, &b| a.max(b))
    }

    /// Mean of velocity component `c` over x (and z) for every y, into `out` (length ny).
    pub fn plane_average(&mut self, c: usize, out: &mut [f64]) {
        let g = self.grid;
        let u = &self.u[c];
        per_row(&mut self.partials, g.rows(), g.nx, |r| {
            ordered_sum(&u[r * g.nx..(r + 1) * g.nx])
        });
        let norm = 1.0 / (g.nx * g.nz) as f64;
        for (y, o) in out.iter_mut().enumerate().take(g.ny) {
            let mut s = 0.0;
            for z in 0..g.nz {
                s += self.partials[z * g.ny + y];
            }
            *o = s * norm;
        }
    }
}

/// Sum and largest of `Σ_c v_c²` over a row of `D` components (lengths equal), in
/// [`LANES`] interleaved lanes: node i adds to lane i mod LANES, the lanes are then added as
/// (0 + 1) + (2 + 3). The largest value is NaN if the sum is.
fn row_energy_and_max<const D: usize>(c: [&[f64]; D]) -> (f64, f64) {
    let n = c[0].len();
    assert!(
        c.iter().all(|s| s.len() == n),
        "components of unequal length"
    );
    let (mut e, mut m) = ([0.0; LANES], [0.0f64; LANES]);
    let mut add = |l: usize, i: usize| {
        let mut s = 0.0;
        for comp in &c {
            s += comp[i] * comp[i];
        }
        e[l] += s;
        m[l] = m[l].max(s);
    };
    let whole = n / LANES * LANES;
    for i in (0..whole).step_by(LANES) {
        for l in 0..LANES {
            add(l, i + l);
        }
    }
    for (l, i) in (whole..n).enumerate() {
        add(l, i);
    }
    let energy = (e[0] + e[1]) + (e[2] + e[3]);
    // `max` drops NaN; the sum keeps it.
    let max = m[0].max(m[1]).max(m[2].max(m[3]));
    (energy, if energy.is_nan() { f64::NAN } else { max })
}

/// Interleaved partial sums per row in [`row_energy_and_max`].
const LANES: usize = 4;

/// The 2D products in the order [`SpectralNs::advection`] transforms them: (a, b) per index.
const PAIRS_2D: [(usize, usize); 3] = [(0, 0), (0, 1), (1, 1)];
/// Index in [`PAIRS_2D`] of the product of components c and e, per c, e.
const PAIR_2D: [[usize; 2]; 2] = [[0, 1], [1, 2]];

/// `-i k p`.
#[inline]
fn minus_i_k(k: f64, p: Complex64) -> Complex64 {
    Complex64::new(k * p.im, -k * p.re)
}

/// Remove the component of `v` along `k`: `v -= k (k·v) / k²`.
#[inline]
fn project<const D: usize>(k: &[f64; D], v: &mut [Complex64; D]) {
    let mut k2 = 0.0;
    let mut kv = Complex64::default();
    for c in 0..D {
        k2 += k[c] * k[c];
        kv += v[c] * k[c];
    }
    if k2 > 0.0 {
        let s = kv / k2;
        for c in 0..D {
            v[c] -= s * k[c];
        }
    }
}

/// The first `D` of (k_x, k_y, k_z).
#[inline]
fn wavevector<const D: usize>(kx: f64, [ky, kz]: [f64; 2]) -> [f64; D] {
    let k = [kx, ky, kz];
    std::array::from_fn(|c| k[c])
}

/// The `D` component rows [`for_each_row`] hands over, as an array.
#[inline]
fn components<'a, 'b, const D: usize>(
    rows: &'a mut [&'b mut [Complex64]],
) -> &'a mut [&'b mut [Complex64]; D] {
    rows.try_into().expect("one row per component")
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn max_rel_err(a: &[f64], b: &[f64]) -> f64 {
        let scale = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        a.iter()
            .zip(b)
            .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
            / scale
    }

    /// 2D Taylor–Green vortex, stream function ψ = sin(kx x) sin(ky y) with kx ≠ ky on a
    /// non-square, non-power-of-two grid: an exact Navier–Stokes solution (the advection term
    /// is a gradient), each velocity component decays as exp(-ν k² t).
    #[test]
    fn taylor_green_2d_decays_exactly() {
        for (nx, ny) in [(24usize, 20usize), (32, 32)] {
            let g = Grid::new(2, [nx, ny, 1]);
            let (nu, dt, steps) = (0.05, 0.5, 200);
            let (kx, ky) = (2.0 * PI / nx as f64, 2.0 * PI / ny as f64 * 2.0);
            let amp = 0.05;
            let tg = |x: usize, y: usize, decay: f64| {
                let (x, y) = (x as f64, y as f64);
                [
                    amp * decay * ky * (kx * x).sin() * (ky * y).cos(),
                    -amp * decay * kx * (kx * x).cos() * (ky * y).sin(),
                    0.0,
                ]
            };
            let mut s = SpectralNs::new(g, nu, dt, [0.0; 3]);
            s.set_velocity(|x, y, _| tg(x, y, 1.0));
            for _ in 0..steps {
                s.advance_intermediate();
            }
            let t = steps as f64 * dt;
            let decay = (-nu * (kx * kx + ky * ky) * t).exp();
            for c in 0..2 {
                let exact: Vec<f64> = (0..g.cells())
                    .map(|i| tg(i % nx, i / nx, decay)[c])
                    .collect();
                let err = max_rel_err(s.velocity(c), &exact);
                eprintln!("Taylor–Green 2D {nx}x{ny}: u_{c} relative error {err:.2e} after decay to {decay:.3}");
                assert!(err < 1e-10, "{err:e}");
            }
            let e0 = 0.5 * (amp * amp) * (kx * kx + ky * ky) / 4.0 * g.cells() as f64;
            let e = s.kinetic_energy(1.0);
            let rel = (e / (e0 * decay * decay) - 1.0).abs();
            eprintln!("  kinetic energy vs exp(-2 nu k^2 t): {rel:.2e}");
            assert!(rel < 1e-10);
            assert!(s.max_divergence() < 1e-15);
        }
    }

    /// 3D: the ABC (Arnold–Beltrami–Childress) flow on a cube, an exact Navier–Stokes
    /// solution (curl u = k u makes the advection term a gradient), decays as exp(-ν k² t);
    /// and a Taylor–Green vortex in the x–z plane on a non-power-of-two box.
    #[test]
    fn beltrami_and_taylor_green_3d_decay_exactly() {
        let n = 12usize;
        let g = Grid::new(3, [n, n, n]);
        let (nu, dt, steps) = (0.05, 0.5, 100);
        let k = 2.0 * PI / n as f64;
        let (a, b, c) = (0.03, 0.02, 0.01);
        let abc = |x: usize, y: usize, z: usize, d: f64| {
            let (x, y, z) = (k * x as f64, k * y as f64, k * z as f64);
            [
                d * (a * z.sin() + c * y.cos()),
                d * (b * x.sin() + a * z.cos()),
                d * (c * y.sin() + b * x.cos()),
            ]
        };
        let mut s = SpectralNs::new(g, nu, dt, [0.0; 3]);
        s.set_velocity(|x, y, z| abc(x, y, z, 1.0));
        for _ in 0..steps {
            s.advance_intermediate();
        }
        let decay = (-nu * k * k * steps as f64 * dt).exp();
        for comp in 0..3 {
            let exact: Vec<f64> = (0..g.cells())
                .map(|i| abc(i % n, (i / n) % n, i / (n * n), decay)[comp])
                .collect();
            let err = max_rel_err(s.velocity(comp), &exact);
            eprintln!("ABC 3D {n}^3: u_{comp} relative error {err:.2e}");
            assert!(err < 1e-10);
        }

        let g = Grid::new(3, [18, 10, 14]);
        let (kx, kz) = (2.0 * PI / 18.0, 2.0 * PI / 14.0);
        let tg = |x: usize, z: usize, d: f64| {
            let (x, z) = (x as f64, z as f64);
            [
                0.05 * d * kz * (kx * x).sin() * (kz * z).cos(),
                0.0,
                -0.05 * d * kx * (kx * x).cos() * (kz * z).sin(),
            ]
        };
        let mut s = SpectralNs::new(g, nu, dt, [0.0; 3]);
        s.set_velocity(|x, _, z| tg(x, z, 1.0));
        for _ in 0..steps {
            s.advance_intermediate();
        }
        let decay = (-nu * (kx * kx + kz * kz) * steps as f64 * dt).exp();
        for comp in [0, 2] {
            let exact: Vec<f64> = (0..g.cells())
                .map(|i| tg(i % 18, i / (18 * 10), decay)[comp])
                .collect();
            let err = max_rel_err(s.velocity(comp), &exact);
            eprintln!("Taylor–Green 3D (x-z) 18x10x14: u_{comp} relative error {err:.2e}");
            assert!(err < 1e-10);
        }
        assert!(s.velocity(1).iter().all(|v| v.abs() < 1e-15));
    }

    /// u* updated on some rows only (the solids' rows of an SPM step) gives those rows the
    /// full update's bits and leaves the others as they were; after the penalty the whole
    /// field has the bits of the full path.
    #[test]
    fn rows_updated_before_the_penalty_end_in_the_full_bits() {
        for g in [Grid::new(2, [24, 20, 1]), Grid::new(3, [10, 12, 9])] {
            let start = || {
                let mut s = SpectralNs::new(g, 0.1, 0.3, [0.0; 3]);
                s.set_velocity(|x, y, z| {
                    let h = |a: usize| ((a * 2654435761) % 1000) as f64 / 1000.0 - 0.3;
                    [h(x + 3 * y + 7 * z), h(5 * x + y + z), h(x + y + 11 * z)]
                });
                s
            };
            let (mut full, mut part) = (start(), start());
            let rows: Vec<bool> = (0..g.rows()).map(|r| r % 3 == 1).collect();
            let before: Vec<Vec<f64>> = part.velocity_components().to_vec();
            full.advance_intermediate();
            part.advance_intermediate_on(&rows);
            let nx = g.nx;
            for c in 0..g.dims {
                for (r, &on) in rows.iter().enumerate() {
                    let row = |v: &[f64]| {
                        v[r * nx..(r + 1) * nx]
                            .iter()
                            .map(|x| x.to_bits())
                            .collect::<Vec<_>>()
                    };
                    let want = if on {
                        row(full.velocity(c))
                    } else {
                        row(&before[c])
                    };
                    assert_eq!(row(part.velocity(c)), want, "{g:?} component {c} row {r}");
                }
            }
            // A penalty that reads u* on the rows flagged in `on` only.
            let penalty = |on: &[bool]| {
                let on = on.to_vec();
                move |c: usize, r: usize, u: &[f64], out: &mut [f64]| {
                    if on[r] {
                        for (o, v) in out.iter_mut().zip(u) {
                            *o = 0.2 * (c as f64 + 1.0) - v;
                        }
                    } else {
                        out.fill(0.0);
                    }
                }
            };
            let same_bits = |part: &SpectralNs, full: &SpectralNs, what: &str| {
                for c in 0..g.dims {
                    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                    let (p, f) = (bits(part.velocity(c)), bits(full.velocity(c)));
                    assert_eq!(p, f, "{g:?} component {c}, {what}");
                }
            };
            let force = penalty(&rows);
            full.add_projected(&[], &force);
            part.add_projected(&rows, &force);
            same_bits(&part, &full, "penalty on the updated rows");
            // A penalty that reads rows the partial update left behind (a sub-cycled fibre's
            // corrected positions): the solver brings them up to date before it reads them.
            let (mut full, mut part) = (start(), start());
            let reads: Vec<bool> = (0..g.rows()).map(|r| r % 3 == 1 || r % 4 == 0).collect();
            full.advance_intermediate();
            part.advance_intermediate_on(&rows);
            let force = penalty(&reads);
            full.add_projected(&[], &force);
            part.add_projected(&reads, &force);
            same_bits(&part, &full, "penalty on rows left behind");
        }
    }

    #[test]
    fn projection_leaves_round_off_divergence_and_keeps_the_mean() {
        for g in [Grid::new(2, [20, 15, 1]), Grid::new(3, [10, 12, 9])] {
            let mut s = SpectralNs::new(g, 0.1, 0.3, [0.0; 3]);
            // A rough, not divergence-free field with a mean.
            s.set_velocity(|x, y, z| {
                let h = |a: usize| ((a * 2654435761) % 1000) as f64 / 1000.0 - 0.3;
                [
                    0.1 * h(x + 3 * y + 7 * z),
                    0.1 * h(5 * x + y + z),
                    0.1 * h(x + y + 11 * z),
                ]
            });
            let m0 = s.mean_velocity();
            let div = s.max_divergence();
            let speed = s.max_speed();
            eprintln!("{g:?}: max |div u| = {div:.2e} for max |u| = {speed:.2e}");
            assert!(div < 1e-15 * 100.0 * speed.max(1.0));
            for _ in 0..5 {
                s.advance_intermediate();
            }
            assert!(s.max_divergence() < 1e-14);
            let m1 = s.mean_velocity();
            for c in 0..3 {
                assert!((m1[c] - m0[c]).abs() < 1e-16, "{m0:?} {m1:?}");
            }
        }
    }

    #[test]
    fn body_force_accelerates_the_mean_exactly() {
        let g = Grid::new(2, [16, 12, 1]);
        let mut s = SpectralNs::new(g, 0.1, 0.25, [2e-3, -1e-3, 0.0]);
        for _ in 0..8 {
            s.advance_intermediate();
        }
        let m = s.mean_velocity();
        assert!((m[0] - 8.0 * 0.25 * 2e-3).abs() < 1e-17);
        assert!((m[1] + 8.0 * 0.25 * 1e-3).abs() < 1e-17);
        // Uniform: no gradients anywhere.
        assert!(s.velocity(0).iter().all(|v| (v - m[0]).abs() < 1e-16));
    }

    /// The lanes of `energy_and_max_speed` against a plain sum and maximum, on rows whose
    /// length is and is not a multiple of the lanes; a NaN anywhere makes both NaN.
    #[test]
    fn energy_and_max_speed_match_a_plain_pass_and_see_nan() {
        for (dims, n) in [(2, [13, 5, 1]), (2, [16, 4, 1]), (3, [6, 4, 3])] {
            let g = Grid::new(dims, n);
            let mut s = SpectralNs::new(g, 1.0, 0.1, [0.0; 3]);
            let field = |x: usize, y: usize, z: usize| {
                let t = (x + 3 * y + 7 * z) as f64;
                [t.sin(), (1.3 * t).cos(), (0.7 * t).sin()]
            };
            s.set_velocity(field);
            let (mut e, mut m) = (0.0, 0.0f64);
            for c in 0..g.cells() {
                let v2: f64 = (0..dims).map(|k| s.velocity(k)[c].powi(2)).sum();
                e += 0.5 * 2.0 * v2;
                m = m.max(v2);
            }
            let (energy, max) = s.energy_and_max_speed(2.0);
            assert!(
                (energy - e).abs() <= 1e-14 * e,
                "{dims}D {n:?}: {energy} {e}"
            );
            assert!((max - m.sqrt()).abs() <= 1e-15 * max, "{dims}D {n:?}");
            assert_eq!(s.kinetic_energy(2.0), energy);
            assert_eq!(s.max_speed(), max);
            let last = g.cells() - 1;
            s.set_velocity(|x, y, z| {
                let mut v = field(x, y, z);
                if x + g.nx * (y + g.ny * z) == last {
                    v[0] = f64::NAN;
                }
                v
            });
            let (energy, max) = s.energy_and_max_speed(2.0);
            assert!(energy.is_nan() && max.is_nan(), "{dims}D {n:?}");
        }
    }
}
