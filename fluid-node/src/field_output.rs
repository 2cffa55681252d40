//! The fluid's fields as VTK image data for ParaView ([`cosim::Command::WriteFields`]): file
//! output between steps, apart from the physics. Nodes sit at integer positions (spacing 1,
//! the scene's length unit), x fastest, as in the solvers, so the beads of the same step
//! (the coordinator's `beads_*.vtp`) fall on the field where the fluid saw them.
//!
//! Arrays (per node):
//! - `velocity`: the flow velocity (x, y, z; z = 0 in 2D), length per time unit; under SPM
//!   after the step's penalty (the velocity the next step starts from);
//! - `solid_fraction`: SPM: the sum of the bead and wall profiles phi (L2020 eq. 25) before
//!   normalisation; FPD: phi = min(1, sum_i phi_i), the field of S2023 eq. 1 (absent without
//!   beads);
//! - `psi` (SPM with `[fluid.binary]`): the order parameter of the binary fluid;
//! - `density` and `viscosity` (FPD): the lattice density and the kinematic viscosity of
//!   S2023 eq. 1 in lattice units.
use cosim::vtk::{self, Array};
use cosim::ComponentError;
use std::path::Path;

/// File name of the fields of the end of `step`.
pub fn file_name(step: u64) -> String {
    format!("fluid_{step:08}.vti")
}

/// Interleave up to three components of `n` values each into (x, y, z) triples, zero where
/// a component is missing (the z of a 2D flow).
pub fn interleave(components: &[&[f64]], n: usize) -> Vec<f64> {
    let mut out = vec![0.0; 3 * n];
    for (c, values) in components.iter().take(3).enumerate() {
        for (i, v) in values.iter().take(n).enumerate() {
            out[3 * i + c] = *v;
        }
    }
    out
}

/// Write `arrays` on a grid of `n` nodes to `dir/name`.
pub fn write(
    dir: &Path,
    name: &str,
    n: [usize; 3],
    arrays: &[Array],
) -> Result<Vec<String>, ComponentError> {
    vtk::write_image(&dir.join(name), n, arrays)
        .map_err(|e| ComponentError::new(format!("fluid-node: writing the fields: {e}")))?;
    Ok(vec![name.to_string()])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interleave_pads_the_missing_component() {
        let v = interleave(&[&[1.0, 2.0], &[3.0, 4.0]], 2);
        assert_eq!(v, [1.0, 3.0, 0.0, 2.0, 4.0, 0.0]);
    }
}
