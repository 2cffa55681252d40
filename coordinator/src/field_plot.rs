//! A PNG picture of a snapshot in an x-y plane (the whole of a 2D grid, the middle plane of a
//! 3D one): the vorticity of the flow, the beads drawn to scale and, in a binary fluid, the
//! interface psi = 0. Written next to each fluid snapshot (field_snapshots.rs) from the file
//! the fluid node wrote, so that a run shows its flow without a viewer.
use plotters::prelude::*;
use std::path::Path;

/// One x-y plane to draw, nodes at integer positions, x fastest.
pub(crate) struct Snapshot<'a> {
    pub nx: usize,
    pub ny: usize,
    /// (u_x, u_y, u_z) per node.
    pub velocity: &'a [f64],
    /// The solid fraction (beads and walls), if the file has it.
    pub solid: Option<&'a [f64]>,
    /// The binary fluid's order parameter, if any.
    pub psi: Option<&'a [f64]>,
    /// Bead centres (x, y) and radii.
    pub beads: &'a [([f64; 2], f64)],
    /// Whether y is periodic (SPM; FPD has walls at the lattice's ends).
    pub periodic_y: bool,
}

/// Vorticity dv/dx - du/dy by central differences, periodic in x, in y periodic or one-sided
/// at the ends.
pub(crate) fn vorticity(s: &Snapshot) -> Vec<f64> {
    let (nx, ny) = (s.nx, s.ny);
    let u = |x: usize, y: usize, c: usize| s.velocity[3 * (y * nx + x) + c];
    let mut w = vec![0.0; nx * ny];
    for y in 0..ny {
        let (ym, yp, dy) = if s.periodic_y || ny < 3 {
            ((y + ny - 1) % ny, (y + 1) % ny, 2.0)
        } else if y == 0 {
            (0, 1, 1.0)
        } else if y == ny - 1 {
            (ny - 2, ny - 1, 1.0)
        } else {
            (y - 1, y + 1, 2.0)
        };
        for x in 0..nx {
            let (xm, xp) = ((x + nx - 1) % nx, (x + 1) % nx);
            let dv_dx = (u(xp, y, 1) - u(xm, y, 1)) / 2.0;
            let du_dy = (u(x, yp, 0) - u(x, ym, 0)) / dy;
            w[y * nx + x] = dv_dx - du_dy;
        }
    }
    w
}

/// Blue (negative) - white - red (positive), `v` in [-1, 1].
fn diverging(v: f64) -> RGBColor {
    let t = v.clamp(-1.0, 1.0);
    let mix = |a: f64, b: f64, f: f64| (a + (b - a) * f).round() as u8;
    if t < 0.0 {
        let f = -t;
        RGBColor(
            mix(255.0, 33.0, f),
            mix(255.0, 102.0, f),
            mix(255.0, 172.0, f),
        )
    } else {
        RGBColor(
            mix(255.0, 178.0, t),
            mix(255.0, 24.0, t),
            mix(255.0, 43.0, t),
        )
    }
}

/// Draw the snapshot's vorticity to `path`, its colour scale at -+ the 99th percentile of
/// |vorticity| in the fluid (solid fraction below 0.01), so that the jumps at the edges of
/// walls and beads do not wash the flow out.
pub(crate) fn draw(path: &Path, title: &str, s: &Snapshot) -> Result<(), String> {
    crate::plot::register_font();
    let w = vorticity(s);
    let fluid = |i: usize| s.solid.is_none_or(|phi| phi[i] < 0.01);
    let mut mags: Vec<f64> = (0..w.len())
        .filter(|&i| fluid(i))
        .map(|i| w[i].abs())
        .filter(|v| v.is_finite())
        .collect();
    mags.sort_unstable_by(f64::total_cmp);
    let scale = mags
        .get(((mags.len() as f64) * 0.99) as usize)
        .copied()
        .filter(|v| *v > 0.0)
        .unwrap_or(1.0);
    // About 600 pixels along the longer side; a node per cell, or every k-th on big grids.
    let (nx, ny) = (s.nx, s.ny);
    let k = nx.max(ny).div_ceil(600).max(1);
    let px = (600.0 / nx.max(ny) as f64).max(1.0);
    let (width, height) = ((nx as f64 * px) as u32 + 215, (ny as f64 * px) as u32 + 110);
    let e = |e: DrawingAreaErrorKind<_>| format!("plotting {}: {e:?}", path.display());
    let root = BitMapBackend::new(path, (width, height)).into_drawing_area();
    root.fill(&WHITE).map_err(e)?;
    let (left, right) = root.split_horizontally(width - 125);
    let mut chart = ChartBuilder::on(&left)
        .caption(title, ("sans-serif", 18))
        .margin(10)
        .x_label_area_size(30)
        .y_label_area_size(45)
        .build_cartesian_2d(0.0..nx as f64, 0.0..ny as f64)
        .map_err(e)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_label_formatter(&|v| format!("{v:.0}"))
        .y_label_formatter(&|v| format!("{v:.0}"))
        .label_style(("sans-serif", 13))
        .draw()
        .map_err(e)?;
    let cells = (0..ny)
        .step_by(k)
        .flat_map(|y| (0..nx).step_by(k).map(move |x| (x, y)));
    chart
        .draw_series(cells.map(|(x, y)| {
            let (x0, y0) = (x as f64, y as f64);
            Rectangle::new(
                [(x0, y0), (x0 + k as f64, y0 + k as f64)],
                diverging(w[y * nx + x] / scale).filled(),
            )
        }))
        .map_err(e)?;
    if let Some(psi) = s.psi {
        // The interface: nodes where psi changes sign towards the next node in x or y.
        let edge = (0..ny)
            .flat_map(|y| (0..nx).map(move |x| (x, y)))
            .filter(|&(x, y)| {
                let p = psi[y * nx + x];
                let right = psi[y * nx + (x + 1) % nx];
                let up = psi[((y + 1) % ny) * nx + x];
                p * right < 0.0 || p * up < 0.0
            });
        chart
            .draw_series(
                edge.map(|(x, y)| Circle::new((x as f64 + 0.5, y as f64 + 0.5), 1, BLACK.filled())),
            )
            .map_err(e)?;
    }
    for &(c, r) in s.beads {
        let ring: Vec<(f64, f64)> = (0..=48)
            .map(|i| {
                let a = i as f64 * std::f64::consts::TAU / 48.0;
                (c[0] + r * a.cos(), c[1] + r * a.sin())
            })
            .collect();
        chart
            .draw_series(std::iter::once(PathElement::new(
                ring,
                BLACK.stroke_width(2),
            )))
            .map_err(e)?;
    }
    // The colour bar.
    let mut bar = ChartBuilder::on(&right)
        .margin_top(40)
        .margin_bottom(40)
        .margin_right(10)
        .y_label_area_size(75)
        .caption("vorticity, 1/time", ("sans-serif", 13))
        .build_cartesian_2d(0.0..1.0, -scale..scale)
        .map_err(e)?;
    bar.configure_mesh()
        .disable_mesh()
        .disable_x_axis()
        .y_label_formatter(&|v| {
            if v.abs() < 1e-6 * scale {
                "0".into()
            } else {
                format!("{v:.1e}")
            }
        })
        .label_style(("sans-serif", 12))
        .draw()
        .map_err(e)?;
    bar.draw_series((0..100).map(|i| {
        let (a, b) = (
            -scale + 2.0 * scale * i as f64 / 100.0,
            -scale + 2.0 * scale * (i + 1) as f64 / 100.0,
        );
        Rectangle::new(
            [(0.0, a), (1.0, b)],
            diverging((a + b) / (2.0 * scale)).filled(),
        )
    }))
    .map_err(e)?;
    root.present().map_err(e)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Simple shear u_x = gamma y has vorticity -gamma everywhere inside; rigid rotation
    /// (u_x, u_y) = Omega (-y, x) has 2 Omega.
    #[test]
    fn vorticity_of_shear_and_rotation() {
        let (nx, ny) = (8, 6);
        let field = |f: &dyn Fn(f64, f64) -> [f64; 2]| -> Vec<f64> {
            (0..ny)
                .flat_map(|y| (0..nx).map(move |x| (x, y)))
                .flat_map(|(x, y)| {
                    let [a, b] = f(x as f64, y as f64);
                    [a, b, 0.0]
                })
                .collect()
        };
        let shear = field(&|_, y| [0.3 * y, 0.0]);
        let s = Snapshot {
            nx,
            ny,
            velocity: &shear,
            solid: None,
            psi: None,
            beads: &[],
            periodic_y: false,
        };
        let w = vorticity(&s);
        assert!(w.iter().all(|v| (v + 0.3).abs() < 1e-12), "{w:?}");
        let spin = field(&|x, y| [-0.2 * y, 0.2 * x]);
        let w = vorticity(&Snapshot {
            velocity: &spin,
            ..s
        });
        // Away from the periodic seam in x.
        for y in 0..ny {
            for x in 1..nx - 1 {
                assert!((w[y * nx + x] - 0.4).abs() < 1e-12);
            }
        }
    }
}
