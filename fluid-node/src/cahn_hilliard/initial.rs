//! Initial order-parameter fields: the equilibrium flat profile `tanh(s / (√2 ξ))` across
//! each interface, with `s` the signed distance to it (positive on the side of the named
//! fluid), minimum-image periodic.
use super::{CahnHilliardError, Fluid};
use crate::grid::Grid;
use std::f64::consts::SQRT_2;

fn check(grid: Grid, psi: &[f64], xi: f64) -> Result<(), CahnHilliardError> {
    if psi.len() != grid.cells() {
        return Err(CahnHilliardError::FieldLength {
            name: "psi",
            expected: grid.cells(),
            got: psi.len(),
        });
    }
    if !(xi.is_finite() && xi > 0.0) {
        return Err(CahnHilliardError::InvalidParameter {
            name: "xi",
            value: xi,
            reason: "must be finite and positive",
        });
    }
    Ok(())
}

/// Fill `psi` with `value(s)` where `s` is a signed distance computed from the
/// minimum-image offset `r = x - centre` of each node (z = 0 in 2D).
fn fill(grid: Grid, psi: &mut [f64], centre: [f64; 3], dist: impl Fn([f64; 3]) -> f64) {
    let n = grid.sizes();
    let wrap = |d: f64, len: usize| {
        let l = len as f64;
        d - l * (d / l).round()
    };
    for z in 0..grid.nz {
        for y in 0..grid.ny {
            for x in 0..grid.nx {
                let mut r = [
                    wrap(x as f64 - centre[0], n[0]),
                    wrap(y as f64 - centre[1], n[1]),
                    wrap(z as f64 - centre[2], n[2]),
                ];
                if grid.dims == 2 {
                    r[2] = 0.0;
                }
                psi[grid.index(x, y, z)] = dist(r);
            }
        }
    }
}

/// Two flat interfaces normal to `axis` (0, 1 or 2): `inside` fills the periodic slab from
/// `from` to `to` along the axis (wrapping when `to < from`), the other fluid the rest; each
/// interface carries the tanh profile (L2020 sections 3.3–3.4: A above, B below).
pub fn stratified(
    grid: Grid,
    xi: f64,
    axis: usize,
    from: f64,
    to: f64,
    inside: Fluid,
    psi: &mut [f64],
) -> Result<(), CahnHilliardError> {
    check(grid, psi, xi)?;
    if axis >= grid.dims {
        return Err(CahnHilliardError::InvalidParameter {
            name: "axis",
            value: axis as f64,
            reason: "must be below the number of dimensions",
        });
    }
    let len = grid.sizes()[axis] as f64;
    let width = (to - from).rem_euclid(len);
    let w = SQRT_2 * xi;
    let sign = inside.psi();
    for z in 0..grid.nz {
        for y in 0..grid.ny {
            for x in 0..grid.nx {
                let c = [x, y, z][axis] as f64;
                let t = (c - from).rem_euclid(len);
                // Distance to the nearer of the two interfaces, positive inside the slab.
                let s = if t < width {
                    t.min(width - t)
                } else {
                    -(t - width).min(len - t)
                };
                psi[grid.index(x, y, z)] = sign * (s / w).tanh();
            }
        }
    }
    Ok(())
}

/// A disk (2D) or sphere (3D) of `inside` fluid, of `radius` around `centre`, in the other
/// fluid.
pub fn droplet(
    grid: Grid,
    xi: f64,
    centre: [f64; 3],
    radius: f64,
    inside: Fluid,
    psi: &mut [f64],
) -> Result<(), CahnHilliardError> {
    check(grid, psi, xi)?;
    let (w, sign) = (SQRT_2 * xi, inside.psi());
    fill(grid, psi, centre, |r| {
        let d = (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]).sqrt();
        sign * ((radius - d) / w).tanh()
    });
    Ok(())
}

/// Half a disk (2D) or a hemisphere (3D) of `inside` fluid: the points within `radius` of
/// `base` on the side `(x - base)·normal > 0` (L2020 section 3.5: the base touches the
/// fibre). The signed distance is `min(radius - |r|, r·n)`, exact inside and a close
/// approximation near the two corners outside.
pub fn half_droplet(
    grid: Grid,
    xi: f64,
    base: [f64; 3],
    normal: [f64; 3],
    radius: f64,
    inside: Fluid,
    psi: &mut [f64],
) -> Result<(), CahnHilliardError> {
    check(grid, psi, xi)?;
    let dims = grid.dims;
    let norm = normal.iter().take(dims).map(|v| v * v).sum::<f64>().sqrt();
    if !(norm.is_finite() && norm > 0.0) {
        return Err(CahnHilliardError::InvalidParameter {
            name: "normal length",
            value: norm,
            reason: "must be finite and positive",
        });
    }
    let n: [f64; 3] = std::array::from_fn(|c| if c < dims { normal[c] / norm } else { 0.0 });
    let (w, sign) = (SQRT_2 * xi, inside.psi());
    fill(grid, psi, base, |r| {
        let d = (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]).sqrt();
        let h = r[0] * n[0] + r[1] * n[1] + r[2] * n[2];
        sign * ((radius - d).min(h) / w).tanh()
    });
    Ok(())
}
