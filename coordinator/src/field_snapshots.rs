//! Snapshots for ParaView (`output.fields_interval`): every so many steps each node writes
//! its fields (the fluid node: `fields/fluid_<step>.vti`, cosim::vtk) and the coordinator
//! writes the beads of the same step (`fields/beads_<step>.vtp`: centres as points and one
//! polyline per fibre, with velocity, angular velocity, radius, fibre and bead number);
//! `DIR/fields.pvd` lists them with their times, so ParaView opens the run as one time
//! series. Each fluid snapshot is also drawn as `fields/fluid_<step>.png` (field_plot.rs; in
//! 3D its middle x-y plane), and the picture logged on the MCAP topic `/fluid/vorticity`.
//! Written between steps, so a snapshot changes no result.
use crate::mcap_log::RunLog;
use crate::runner::{fail, Node, RunError};
use cosim::vtk::{self, Array, Values};
use cosim::{BeadState, Command, Reply};
use std::path::{Path, PathBuf};

/// Subfolder of the output directory that holds the snapshot files.
const FOLDER: &str = "fields";
/// The collection file in the output directory.
pub(crate) const COLLECTION: &str = "fields.pvd";

pub(crate) struct Snapshots {
    out: PathBuf,
    /// Steps between snapshots.
    every: u64,
    /// (time, part, file relative to `out`) of every file written.
    entries: Vec<(f64, usize, String)>,
    /// Whether the fluid's y axis is periodic (no bounce-back walls at the lattice's ends).
    periodic_y: bool,
    /// Why a picture could not be drawn (the run goes on; the summary's `file_errors`).
    pub(crate) picture_error: Option<String>,
}

impl Snapshots {
    /// `None` when the scene asks for no snapshots (`every` = 0).
    /// `periodic_y`: whether the fluid's y axis is periodic (for the pictures' vorticity).
    pub(crate) fn new(out: &Path, every: u64, periodic_y: bool) -> Option<Self> {
        (every > 0).then(|| Self {
            out: out.to_path_buf(),
            every,
            entries: Vec::new(),
            periodic_y,
            picture_error: None,
        })
    }

    /// A resumed run into the same output directory: keep the snapshots its collection lists
    /// up to `time` (the checkpoint's), so that the series runs on from them.
    pub(crate) fn keep_earlier(&mut self, time: f64) {
        let Ok(xml) = std::fs::read_to_string(self.out.join(COLLECTION)) else {
            return;
        };
        for line in xml.lines().filter(|l| l.starts_with("<DataSet ")) {
            let attr = |k| vtk::attribute(line, k);
            if let (Some(t), Some(part), Some(file)) = (
                attr("timestep").and_then(|t| t.parse::<f64>().ok()),
                attr("part").and_then(|p| p.parse::<usize>().ok()),
                attr("file"),
            ) {
                if t <= time {
                    self.entries.push((t, part, file.to_string()));
                }
            }
        }
    }

    /// Whether the end of step `step_end` (1-based) gets a snapshot; `last`: the run ends there.
    pub(crate) fn due(&self, step_end: u64, last: bool) -> bool {
        step_end.is_multiple_of(self.every) || last
    }

    /// Steps between snapshots (the batches of steps end there, as at a checkpoint).
    pub(crate) fn every(&self) -> u64 {
        self.every
    }

    /// Write the snapshot of the end of step `step`, time `time`: each node's fields, the
    /// beads (`beads`: beads per fibre, `radii`: each fibre's bead radius; `states`), the
    /// collection so far, and the picture of the fluid (also logged on `/fluid/vorticity`).
    pub(crate) fn write(
        &mut self,
        (step, time): (u64, f64),
        nodes: &mut [Node],
        (beads, radii): (&[usize], &[f64]),
        states: &[BeadState],
        log: &mut RunLog,
    ) -> Result<(), RunError> {
        let dir = self.out.join(FOLDER);
        std::fs::create_dir_all(&dir)
            .map_err(|e| fail(format!("cannot create {}: {e}", dir.display())))?;
        let mut files = Vec::new();
        for n in nodes.iter_mut() {
            let name = n.link.name().to_string();
            let command = Command::WriteFields {
                step,
                time,
                dir: dir.display().to_string(),
            };
            match n.link.call(&command) {
                Ok(Reply::Files(f)) => files.extend(f),
                Ok(Reply::Error(e)) => {
                    return Err(fail(format!("fields at step {step}: node `{name}`: {e}")))
                }
                Ok(other) => {
                    return Err(fail(format!(
                        "fields at step {step}: node `{name}` answered {other:?} to write-fields"
                    )))
                }
                Err(e) => return Err(fail(format!("fields at step {step}: {e}"))),
            }
        }
        // Each bead's radius, for the picture and the beads' file.
        let radius: Vec<f64> = beads
            .iter()
            .enumerate()
            .flat_map(|(f, &n)| std::iter::repeat_n(radii.get(f).copied().unwrap_or(1.0), n))
            .collect();
        let discs: Vec<([f64; 3], f64)> = states
            .iter()
            .map(|s| s.position)
            .zip(radius.iter().copied())
            .collect();
        for f in files.iter().filter(|f| f.ends_with(".vti")) {
            let png = dir.join(f.replace(".vti", ".png"));
            // Six decimals at most: dt = 0.7 makes t = 15749.999999999998 at step 22500.
            let title = format!("step {step}, t = {}", (time * 1e6).round() / 1e6);
            let drawn = picture(&dir.join(f), &png, &title, &discs, self.periodic_y)
                .and_then(|()| std::fs::read(&png).map_err(|e| format!("{}: {e}", png.display())));
            match drawn {
                Ok(bytes) => log.vorticity_picture(time, &bytes).map_err(fail)?,
                Err(e) => {
                    self.picture_error.get_or_insert(e);
                }
            }
        }
        if !states.is_empty() {
            let name = format!("beads_{step:08}.vtp");
            write_beads(&dir.join(&name), beads, &radius, states).map_err(fail)?;
            files.push(name);
        }
        for f in files {
            let part = self.entries.iter().filter(|e| e.0 == time).count();
            self.entries.push((time, part, format!("{FOLDER}/{f}")));
        }
        vtk::write_collection(&self.out.join(COLLECTION), &self.entries).map_err(fail)
    }

    /// The collection, for the summary's `files`, once something was written.
    pub(crate) fn files(&self) -> Vec<String> {
        if self.entries.is_empty() {
            Vec::new()
        } else {
            vec![COLLECTION.to_string()]
        }
    }
}

/// Draw the fluid snapshot `vti` to `png`: the whole of a 2D one, the middle x-y plane of a
/// 3D one (the plane of the shear), with the beads (centre, radius) that cut it.
fn picture(
    vti: &Path,
    png: &Path,
    title: &str,
    beads: &[([f64; 3], f64)],
    periodic_y: bool,
) -> Result<(), String> {
    let [nx, ny, nz] = vtk::image_size(vti)?;
    let arrays = vtk::read_arrays(vti)?;
    // The plane z = k: nodes k nx ny .. (k + 1) nx ny of each array.
    let k = nz / 2;
    let plane = |name: &str| {
        arrays.iter().find(|(n, _)| n == name).map(|(_, v)| {
            let per = v.len() / (nx * ny * nz);
            &v[k * nx * ny * per..(k + 1) * nx * ny * per]
        })
    };
    let velocity = plane("velocity").ok_or_else(|| format!("{}: no velocity", vti.display()))?;
    let discs: Vec<([f64; 2], f64)> = beads
        .iter()
        .filter_map(|&(c, r)| {
            let dz = if nz > 1 { c[2] - k as f64 } else { 0.0 };
            (dz.abs() < r).then(|| ([c[0], c[1]], (r * r - dz * dz).sqrt()))
        })
        .collect();
    let title = if nz > 1 {
        format!("{title}, plane z = {k}")
    } else {
        title.to_string()
    };
    crate::field_plot::draw(
        png,
        &title,
        &crate::field_plot::Snapshot {
            nx,
            ny,
            velocity,
            solid: plane("solid_fraction"),
            psi: plane("psi"),
            beads: &discs,
            periodic_y,
        },
    )
}

/// The beads as points, a polyline per fibre (`beads`: beads per fibre; `radius`: per bead).
fn write_beads(
    path: &Path,
    beads: &[usize],
    radius: &[f64],
    states: &[BeadState],
) -> Result<(), String> {
    let positions: Vec<f64> = states.iter().flat_map(|s| s.position).collect();
    let velocity: Vec<f64> = states.iter().flat_map(|s| s.velocity).collect();
    let spin: Vec<f64> = states.iter().flat_map(|s| s.angular_velocity).collect();
    let (mut fibre, mut bead) = (Vec::new(), Vec::new());
    for (f, &n) in beads.iter().enumerate() {
        for b in 0..n {
            fibre.push(f as i64);
            bead.push(b as i64);
        }
    }
    let int = |name, v| Array {
        name,
        components: 1,
        values: Values::I64(v),
    };
    vtk::write_points(
        path,
        &positions,
        beads,
        &[
            Array::vector("velocity", &velocity),
            Array::vector("angular_velocity", &spin),
            Array::scalar("radius", radius),
            int("fibre", &fibre),
            int("bead", &bead),
        ],
    )
}
