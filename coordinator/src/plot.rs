//! PNG plots with a font shipped in the binary (no system font lookup).
use plotters::prelude::*;
use std::path::Path;
use std::sync::Once;

static FONT: Once = Once::new();

pub(crate) fn register_font() {
    FONT.call_once(|| {
        let bytes: &'static [u8] = include_bytes!("../assets/DejaVuSans.ttf");
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, bytes);
    });
}

/// Build a chart from `$builder` on linear or logarithmic axes, as `$log_x` and `$log_y`
/// say, and run `$body` with it bound to `$chart`. Plotters' linear and logarithmic axes are
/// different types, so the body is expanded once per combination.
macro_rules! on_axes {
    ($builder:expr, $e:expr, ($x0:expr, $x1:expr, $log_x:expr), ($y0:expr, $y1:expr, $log_y:expr),
     |$chart:ident| $body:block) => {
        match ($log_x, $log_y) {
            (true, true) => {
                let mut $chart = $builder
                    .build_cartesian_2d(($x0..$x1).log_scale(), ($y0..$y1).log_scale())
                    .map_err($e)?;
                $body
            }
            (true, false) => {
                let mut $chart = $builder
                    .build_cartesian_2d(($x0..$x1).log_scale(), $y0..$y1)
                    .map_err($e)?;
                $body
            }
            (false, true) => {
                let mut $chart = $builder
                    .build_cartesian_2d($x0..$x1, ($y0..$y1).log_scale())
                    .map_err($e)?;
                $body
            }
            (false, false) => {
                let mut $chart = $builder
                    .build_cartesian_2d($x0..$x1, $y0..$y1)
                    .map_err($e)?;
                $body
            }
        }
    };
}

/// Draw `$chart`'s legend in the plots' common style at `$position`.
macro_rules! legend {
    ($chart:expr, $e:expr, $position:expr) => {
        $chart
            .configure_series_labels()
            .position($position)
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .label_font(("sans-serif", 15))
            .draw()
            .map_err($e)?
    };
}

/// Margin and label areas of an orbit-plot panel (pixels).
const PANEL_MARGIN: u32 = 15;
const PANEL_X_LABELS: u32 = 40;
const PANEL_Y_LABELS: u32 = 70;

/// A panel of the orbit plot: margins and room for the axis labels, the same in every panel
/// so that their gamma t axes line up.
fn panel<'a, 'b>(
    area: &'a DrawingArea<BitMapBackend<'b>, plotters::coord::Shift>,
) -> ChartBuilder<'a, 'b, BitMapBackend<'b>> {
    let mut builder = ChartBuilder::on(area);
    builder
        .margin(PANEL_MARGIN)
        .x_label_area_size(PANEL_X_LABELS)
        .y_label_area_size(PANEL_Y_LABELS);
    builder
}

/// The layout every single-panel plot shares: title, margins, room for the axis labels.
fn titled_chart<'a, 'b>(
    root: &'a DrawingArea<BitMapBackend<'b>, plotters::coord::Shift>,
    title: &str,
) -> ChartBuilder<'a, 'b, BitMapBackend<'b>> {
    let mut builder = ChartBuilder::on(root);
    builder
        .caption(title, ("sans-serif", 22))
        .margin(20)
        .x_label_area_size(50)
        .y_label_area_size(80);
    builder
}

/// One labelled point of an error-against-cost plot.
pub struct CostPoint {
    pub wall_seconds: f64,
    pub error: f64,
    pub label: String,
}

/// Log-log plot of relative error against wall time, each point labelled.
pub fn error_against_time(
    path: &Path,
    title: &str,
    y_label: &str,
    points: &[CostPoint],
) -> Result<(), String> {
    register_font();
    let pts: Vec<&CostPoint> = points
        .iter()
        .filter(|p| p.error.is_finite() && p.wall_seconds > 0.0)
        .collect();
    if pts.is_empty() {
        return Err(
            "nothing to plot: no variant has a finite error and a positive wall time".into(),
        );
    }
    let floor = 1e-12;
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for p in &pts {
        x0 = x0.min(p.wall_seconds);
        x1 = x1.max(p.wall_seconds);
        y0 = y0.min(p.error.max(floor));
        y1 = y1.max(p.error.max(floor));
    }
    let (x0, x1) = with_a_decade(x0 / 1.5, x1 * 4.0);
    let (y0, y1) = with_a_decade(y0 / 3.0, y1 * 3.0);
    let e = |e: DrawingAreaErrorKind<_>| format!("plotting {}: {e:?}", path.display());
    let root = BitMapBackend::new(path, (900, 600)).into_drawing_area();
    root.fill(&WHITE).map_err(e)?;
    let mut chart = titled_chart(&root, title)
        .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_labels(6)
        .y_labels(8)
        .x_desc("wall time (s)")
        .y_desc(y_label)
        .label_style(("sans-serif", 15))
        .x_label_formatter(&|v| format!("{v:.2e}"))
        .y_label_formatter(&|v| format!("{v:.1e}"))
        .draw()
        .map_err(e)?;
    let series: Vec<(f64, f64)> = pts
        .iter()
        .map(|p| (p.wall_seconds, p.error.max(floor)))
        .collect();
    chart
        .draw_series(LineSeries::new(series.clone(), BLUE.mix(0.4)))
        .map_err(e)?;
    chart
        .draw_series(
            series
                .iter()
                .map(|&(x, y)| Circle::new((x, y), 5, BLUE.filled())),
        )
        .map_err(e)?;
    for (p, &(x, y)) in pts.iter().zip(&series) {
        chart
            .draw_series(std::iter::once(Text::new(
                p.label.clone(),
                (x, y),
                ("sans-serif", 14).into_font(),
            )))
            .map_err(e)?;
    }
    root.present().map_err(e)?;
    Ok(())
}

/// One point of a regime map: where it lies and which class the run fell in.
pub struct ClassPoint {
    pub x: f64,
    pub y: f64,
    pub class: String,
}

/// Colour of a class: S2023 Fig. 10a's orbits get fixed colours, other labels follow.
fn class_colour(class: &str, others: &mut Vec<String>) -> RGBColor {
    match class {
        "jeffery" => RGBColor(31, 119, 180),
        "s-turn" => RGBColor(255, 127, 14),
        "s-coiled" => RGBColor(44, 160, 44),
        "stuck" => RGBColor(214, 39, 40),
        other => {
            let palette = [
                RGBColor(148, 103, 189),
                RGBColor(140, 86, 75),
                RGBColor(127, 127, 127),
                RGBColor(23, 190, 207),
            ];
            let i = match others.iter().position(|o| o == other) {
                Some(i) => i,
                None => {
                    others.push(other.to_string());
                    others.len() - 1
                }
            };
            palette[i % palette.len()]
        }
    }
}

/// A logarithmic axis range `lo..hi` (both positive) widened to the powers of ten around it
/// if it holds none: a log axis is labelled at powers of ten only, so a range such as
/// 1.1..6.5 (every run of a study costing the same) would carry no label at all.
fn with_a_decade(lo: f64, hi: f64) -> (f64, f64) {
    let below = 10f64.powf(lo.log10().floor());
    let above = 10f64.powf(hi.log10().ceil());
    let holds_one = 10f64.powf(lo.log10().ceil()) <= hi;
    if holds_one || !(lo > 0.0 && hi.is_finite()) {
        (lo, hi)
    } else {
        (below, above)
    }
}

/// An axis range around `values` with a margin: a factor 3 on a logarithmic axis, a tenth
/// of the span on a linear one (half the value, or 1, for a single value).
fn axis_range(values: impl Iterator<Item = f64>, log: bool) -> (f64, f64) {
    let (lo, hi) = values.fold((f64::MAX, f64::MIN), |(a, b), x| (a.min(x), b.max(x)));
    if log {
        with_a_decade(lo / 3.0, hi * 3.0)
    } else {
        let pad = if hi > lo {
            0.1 * (hi - lo)
        } else {
            0.5 * lo.abs().max(1.0)
        };
        (lo - pad, hi + pad)
    }
}

/// Where a regime map's legend covers the fewest points: the points' places as fractions
/// of the axes (0 to 1, log where the axis is), against the box a legend of `rows` classes
/// takes at each candidate position, and how many it covers there. MiddleRight first, so
/// that a map with room there keeps it.
fn legend_place(places: &[(f64, f64)], rows: usize) -> (SeriesLabelPosition, usize) {
    use SeriesLabelPosition::*;
    let (w, h, r) = (0.17, legend_height(rows), POINT_RADIUS);
    let span = |lo: f64, len: f64| (lo - r, lo + len + r);
    let (left, right) = (span(0.0, w), span(1.0 - w, w));
    let (lower, upper, middle) = (span(0.0, h), span(1.0 - h, h), span(0.5 - h / 2.0, h));
    let centre = span(0.5 - w / 2.0, w);
    let candidates = [
        (MiddleRight, right, middle),
        (UpperRight, right, upper),
        (LowerRight, right, lower),
        (UpperLeft, left, upper),
        (LowerLeft, left, lower),
        (MiddleLeft, left, middle),
        (UpperMiddle, centre, upper),
        (LowerMiddle, centre, lower),
    ];
    let inside = |(a, b): (f64, f64), v: f64| a <= v && v <= b;
    let mut best = (usize::MAX, MiddleRight);
    for (place, xs, ys) in candidates {
        let covered = places
            .iter()
            .filter(|&&(x, y)| inside(xs, x) && inside(ys, y))
            .count();
        if covered < best.0 {
            best = (covered, place);
        }
    }
    (best.1, best.0)
}

/// A regime map's legend of `rows` classes, its height as a fraction of the plotting area
/// (about 25 px a row and 20 px of margin, of ~470 px; its width is about 0.17 of ~780 px).
fn legend_height(rows: usize) -> f64 {
    (25.0 * rows as f64 + 20.0) / 470.0
}

/// A regime map point's radius as a fraction of the plotting area.
const POINT_RADIUS: f64 = 0.02;

/// A regime map: every point coloured by its class, with a legend (S2023 Fig. 10a style).
/// `x` and `y` are (axis name, logarithmic).
pub fn regime_map(
    path: &Path,
    title: &str,
    x: (&str, bool),
    y: (&str, bool),
    points: &[ClassPoint],
) -> Result<(), String> {
    register_font();
    let ok = |v: f64, log: bool| v.is_finite() && (!log || v > 0.0);
    let pts: Vec<&ClassPoint> = points
        .iter()
        .filter(|p| ok(p.x, x.1) && ok(p.y, y.1))
        .collect();
    if pts.is_empty() {
        return Err("nothing to plot: no variant reported both diagram coordinates".into());
    }
    // Axis ranges with a margin: a factor on a log axis, a fraction of the span otherwise.
    let (x0, x1) = axis_range(pts.iter().map(|p| p.x), x.1);
    let (y0, mut y1) = axis_range(pts.iter().map(|p| p.y), y.1);
    let fraction = |v: f64, (lo, hi): (f64, f64), log: bool| {
        if log {
            (v / lo).ln() / (hi / lo).ln()
        } else {
            (v - lo) / (hi - lo)
        }
    };
    let places: Vec<(f64, f64)> = pts
        .iter()
        .map(|p| (fraction(p.x, (x0, x1), x.1), fraction(p.y, (y0, y1), y.1)))
        .collect();
    let mut classes: Vec<(String, RGBColor)> = Vec::new();
    let mut others = Vec::new();
    for p in &pts {
        if !classes.iter().any(|(c, _)| *c == p.class) {
            let colour = class_colour(&p.class, &mut others);
            classes.push((p.class.clone(), colour));
        }
    }
    // No free place for the legend: raise the top of the y axis so that the points leave
    // the upper right to it.
    let legend_at = match legend_place(&places, classes.len()) {
        (place, 0) => place,
        _ => {
            let keep = 1.0 - legend_height(classes.len()) - 2.0 * POINT_RADIUS;
            y1 = if y.1 {
                y0 * (y1 / y0).powf(1.0 / keep)
            } else {
                y0 + (y1 - y0) / keep
            };
            SeriesLabelPosition::UpperRight
        }
    };
    let e = |e: DrawingAreaErrorKind<_>| format!("plotting {}: {e:?}", path.display());
    let root = BitMapBackend::new(path, (900, 600)).into_drawing_area();
    root.fill(&WHITE).map_err(e)?;
    let mut builder = titled_chart(&root, title);
    on_axes!(builder, e, (x0, x1, x.1), (y0, y1, y.1), |chart| {
        chart
            .configure_mesh()
            .x_desc(x.0)
            .y_desc(y.0)
            .label_style(("sans-serif", 15))
            .x_label_formatter(&|v| format!("{v:.2e}"))
            .y_label_formatter(&|v| fixed(*v, 2))
            .draw()
            .map_err(e)?;
        for (class, colour) in &classes {
            let c = *colour;
            chart
                .draw_series(
                    pts.iter()
                        .filter(|p| p.class == *class)
                        .map(|p| Circle::new((p.x, p.y), 8, c.filled())),
                )
                .map_err(e)?
                .label(class.clone())
                .legend(move |(px, py)| Circle::new((px, py), 6, c.filled()));
        }
        legend!(chart, e, legend_at);
    });
    root.present().map_err(e)?;
    Ok(())
}

/// Fibre 0's orbit in four panels: S2023 Fig. 5a (`omega / gamma` against the direction,
/// with eq. 19 for the fitted aspect ratio `fit`, the geometric one `geometric` and a
/// reference value `(r_c, source)` if given); the direction and the end-to-end distance
/// against `gamma t`; and the fibre's `shapes` (`gamma t`, bead centres) drawn to scale at
/// their `gamma t`, first bead marked (S2023 Fig. 7a).
pub fn orbit(
    path: &Path,
    title: &str,
    rows: &crate::orbit_report::OrbitRows,
    shapes: &[(f64, Vec<[f64; 2]>)],
    fit: Option<f64>,
    geometric: f64,
    reference: Option<(f64, &str)>,
) -> Result<(), String> {
    register_font();
    if rows.is_empty() {
        return Err("nothing to plot: the orbit has no samples".into());
    }
    let e = drawing_error(path);
    let root = BitMapBackend::new(path, (900, 1450)).into_drawing_area();
    root.fill(&WHITE).map_err(e)?;
    let root = root.titled(title, ("sans-serif", 22)).map_err(e)?;
    // Three panels of curves, then a lower one for the shapes.
    let h = root.dim_in_pixel().1 as f64;
    let panels = root.split_by_breakpoints(
        [] as [i32; 0],
        [0.27, 0.54, 0.81].map(|f| (f * h).round() as i32),
    );
    let (t0, t1) = finite_range(&rows.gamma_t);
    let gamma_t = (t0, if t1 > t0 { t1 } else { t0 + 1.0 });
    omega_panel(&panels[0], path, rows, fit, geometric, reference)?;
    direction_panel(&panels[1], path, rows, gamma_t)?;
    end_to_end_panel(&panels[2], path, rows, gamma_t)?;
    if !shapes.is_empty() {
        shapes_panel(&panels[3], path, shapes, gamma_t)?;
    }
    root.present().map_err(e)?;
    Ok(())
}

/// One area of a drawing (a panel of a plot).
type Area<'b> = DrawingArea<BitMapBackend<'b>, plotters::coord::Shift>;

/// A drawing error as the message a plot of `path` returns.
fn drawing_error<E: std::error::Error + Send + Sync>(
    path: &Path,
) -> impl Fn(DrawingAreaErrorKind<E>) -> String + Copy + '_ {
    move |e| format!("plotting {}: {e:?}", path.display())
}

/// Smallest and largest finite value of `v`.
fn finite_range(v: &[f64]) -> (f64, f64) {
    v.iter()
        .copied()
        .filter(|x| x.is_finite())
        .fold((f64::MAX, f64::MIN), |(a, b), x| (a.min(x), b.max(x)))
}

/// `(lo, hi)` widened to at least `min_span`, with 5 % room either side.
fn padded((lo, hi): (f64, f64), min_span: f64) -> (f64, f64) {
    let span = (hi - lo).max(min_span);
    let mid = 0.5 * (lo + hi);
    (mid - 0.55 * span, mid + 0.55 * span)
}

/// S2023 eq. 19 for aspect ratio `r_c`: `omega / gamma` over the directions -90 to 90 deg.
fn jeffery_line(r_c: f64) -> Vec<(f64, f64)> {
    (0..=360)
        .map(|i| {
            let th = -90.0 + 0.5 * i as f64;
            (th, crate::orbit_report::jeffery_omega_over_gamma(r_c, th))
        })
        .collect()
}

/// Panel (a) of [`orbit`]: `omega / gamma` against the direction, S2023 Fig. 5a.
fn omega_panel(
    area: &Area,
    path: &Path,
    rows: &crate::orbit_report::OrbitRows,
    fit: Option<f64>,
    geometric: f64,
    reference: Option<(f64, &str)>,
) -> Result<(), String> {
    let e = drawing_error(path);
    let points = rows.orbit_points();
    let omegas: Vec<f64> = points.iter().map(|p| p.1).collect();
    let (w0, w1) = finite_range(&omegas);
    let (w0, w1) = padded((w0.min(-1.0), w1.max(0.0)), 0.1);
    // Room above the curves for the legend.
    let w1 = w1 + 0.3 * (w1 - w0);
    let mut chart = panel(area)
        .build_cartesian_2d(-90.0..90.0, w0..w1)
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc("direction theta (deg, from +x)")
        .y_desc("omega / gamma")
        .label_style(("sans-serif", 15))
        .y_label_formatter(&|v| fixed(*v, 2))
        .draw()
        .map_err(e)?;
    chart
        .draw_series(
            points
                .iter()
                .map(|&(t, w)| Circle::new((t, w), 2, BLUE.filled())),
        )
        .map_err(e)?
        .label("measured")
        .legend(|(x, y)| Circle::new((x, y), 4, BLUE.filled()));
    if let Some(r) = fit {
        chart
            .draw_series(LineSeries::new(jeffery_line(r), RED.stroke_width(2)))
            .map_err(e)?
            .label(format!("S2023 eq. 19, fitted r_c = {r:.3}"))
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RED.stroke_width(2)));
    }
    chart
        .draw_series(DashedLineSeries::new(
            jeffery_line(geometric),
            6,
            4,
            BLACK.stroke_width(1),
        ))
        .map_err(e)?
        .label(format!("S2023 eq. 19, geometric r_c = {geometric:.3}"))
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK));
    if let Some((r, source)) = reference {
        let green = RGBColor(44, 160, 44);
        chart
            .draw_series(DashedLineSeries::new(
                jeffery_line(r),
                10,
                5,
                green.stroke_width(2),
            ))
            .map_err(e)?
            .label(format!("S2023 eq. 19, r_c = {r:.3} ({source})"))
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], green.stroke_width(2))
            });
    }
    legend!(chart, e, SeriesLabelPosition::UpperLeft);
    Ok(())
}

/// Panel (b) of [`orbit`]: the direction against `gamma t` over `(t0, t1)`.
fn direction_panel(
    area: &Area,
    path: &Path,
    rows: &crate::orbit_report::OrbitRows,
    (t0, t1): (f64, f64),
) -> Result<(), String> {
    let e = drawing_error(path);
    let mut chart = panel(area)
        .build_cartesian_2d(t0..t1, -90.0..90.0)
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc("gamma t")
        .y_desc("direction theta (deg)")
        .label_style(("sans-serif", 15))
        .draw()
        .map_err(e)?;
    chart
        .draw_series(
            rows.gamma_t
                .iter()
                .zip(&rows.direction_deg)
                .map(|(&t, &d)| Circle::new((t, d), 1, BLUE.filled())),
        )
        .map_err(e)?;
    Ok(())
}

/// Panel (c) of [`orbit`]: the end-to-end distance against `gamma t` over `(t0, t1)`, with
/// the orbit analysis's fold threshold.
fn end_to_end_panel(
    area: &Area,
    path: &Path,
    rows: &crate::orbit_report::OrbitRows,
    (t0, t1): (f64, f64),
) -> Result<(), String> {
    let e = drawing_error(path);
    let fold = crate::orbit::FOLD_RATIO;
    let (r0, r1) = finite_range(&rows.end_to_end);
    let (r0, r1) = padded((r0.min(fold), r1.max(1.0)), 0.02);
    let mut chart = panel(area).build_cartesian_2d(t0..t1, r0..r1).map_err(e)?;
    chart
        .configure_mesh()
        .x_desc("gamma t")
        .y_desc("end-to-end / contour")
        .label_style(("sans-serif", 15))
        .y_label_formatter(&|v| fixed(*v, 3))
        .draw()
        .map_err(e)?;
    chart
        .draw_series(LineSeries::new(
            rows.gamma_t
                .iter()
                .copied()
                .zip(rows.end_to_end.iter().copied()),
            BLUE.stroke_width(2),
        ))
        .map_err(e)?;
    chart
        .draw_series(DashedLineSeries::new(
            vec![(t0, fold), (t1, fold)],
            6,
            4,
            RED.stroke_width(1),
        ))
        .map_err(e)?;
    chart
        .draw_series(std::iter::once(Text::new(
            format!("fold threshold {fold}"),
            (t0 + 0.01 * (t1 - t0), fold + 0.03 * (r1 - r0)),
            ("sans-serif", 14).into_font().color(&RED),
        )))
        .map_err(e)?;
    Ok(())
}

/// Panel (d) of [`orbit`]: the shapes, each centred on its `gamma t` within `(t0, t1)`, to
/// one scale on both axes, first bead marked.
fn shapes_panel(
    area: &Area,
    path: &Path,
    shapes: &[(f64, Vec<[f64; 2]>)],
    (t0, t1): (f64, f64),
) -> Result<(), String> {
    let e = drawing_error(path);
    let contour = |c: &[[f64; 2]]| -> f64 {
        c.windows(2)
            .map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]))
            .sum()
    };
    let longest = shapes
        .iter()
        .map(|(_, c)| contour(c))
        .fold(0.0, f64::max)
        .max(1e-12);
    let spacing = (t1 - t0) / shapes.len().max(2).saturating_sub(1) as f64;
    let scale = 0.85 * spacing / longest;
    let (x0, x1) = (t0 - 0.5 * spacing, t1 + 0.5 * spacing);
    // The plotting area's size in pixels: the panel less margins and label areas.
    let (w, h) = area.dim_in_pixel();
    let (pw, ph) = (
        w.saturating_sub(2 * PANEL_MARGIN + PANEL_Y_LABELS).max(1) as f64,
        h.saturating_sub(2 * PANEL_MARGIN + PANEL_X_LABELS).max(1) as f64,
    );
    let half = 0.5 * (x1 - x0) * ph / pw;
    let mut chart = panel(area)
        .build_cartesian_2d(x0..x1, -half..half)
        .map_err(e)?;
    chart
        .configure_mesh()
        .disable_y_mesh()
        .x_desc("gamma t (shapes to scale, first bead marked)")
        .y_desc("fibre shape")
        .y_labels(0)
        .label_style(("sans-serif", 15))
        .draw()
        .map_err(e)?;
    for (gt, centres) in shapes {
        let n = centres.len().max(1) as f64;
        let cx = centres.iter().map(|p| p[0]).sum::<f64>() / n;
        let cy = centres.iter().map(|p| p[1]).sum::<f64>() / n;
        let pts: Vec<(f64, f64)> = centres
            .iter()
            .map(|p| (gt + scale * (p[0] - cx), scale * (p[1] - cy)))
            .collect();
        chart
            .draw_series(LineSeries::new(pts.clone(), BLUE.stroke_width(2)))
            .map_err(e)?;
        chart
            .draw_series(pts.iter().map(|&p| Circle::new(p, 2, BLUE.filled())))
            .map_err(e)?;
        if let Some(&first) = pts.first() {
            chart
                .draw_series(std::iter::once(Circle::new(first, 4, RED.filled())))
                .map_err(e)?;
        }
    }
    Ok(())
}

/// A metric against a parameter (a study's `[curve]`): the variants as points joined in order
/// of `x`, and the reference as a dashed line if there is one. `x` and `y` are (axis name,
/// logarithmic).
pub fn metric_against(
    path: &Path,
    title: &str,
    x: (&str, bool),
    y: (&str, bool),
    points: &[(f64, f64)],
    reference: Option<f64>,
) -> Result<(), String> {
    register_font();
    let ok = |v: f64, log: bool| v.is_finite() && (!log || v > 0.0);
    let mut pts: Vec<(f64, f64)> = points
        .iter()
        .copied()
        .filter(|&(a, b)| ok(a, x.1) && ok(b, y.1))
        .collect();
    if pts.is_empty() {
        return Err("nothing to plot: no variant reported the curve's abscissa and a value".into());
    }
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (x0, x1) = axis_range(pts.iter().map(|p| p.0), x.1);
    let (y0, y1) = axis_range(
        pts.iter()
            .map(|p| p.1)
            .chain(reference.filter(|r| ok(*r, y.1))),
        y.1,
    );
    let e = |e: DrawingAreaErrorKind<_>| format!("plotting {}: {e:?}", path.display());
    let root = BitMapBackend::new(path, (900, 600)).into_drawing_area();
    root.fill(&WHITE).map_err(e)?;
    let mut builder = titled_chart(&root, title);
    on_axes!(builder, e, (x0, x1, x.1), (y0, y1, y.1), |chart| {
        chart
            .configure_mesh()
            .x_desc(x.0)
            .y_desc(y.0)
            .label_style(("sans-serif", 15))
            .y_label_formatter(&|v| fixed(*v, 3))
            .draw()
            .map_err(e)?;
        chart
            .draw_series(LineSeries::new(pts.clone(), BLUE.mix(0.5)))
            .map_err(e)?;
        chart
            .draw_series(pts.iter().map(|&p| Circle::new(p, 5, BLUE.filled())))
            .map_err(e)?
            .label(y.0)
            .legend(|(px, py)| Circle::new((px, py), 5, BLUE.filled()));
        if let Some(r) = reference {
            chart
                .draw_series(DashedLineSeries::new(
                    vec![(x0, r), (x1, r)],
                    8,
                    5,
                    RED.stroke_width(2),
                ))
                .map_err(e)?
                .label(format!("reference {r}"))
                .legend(|(px, py)| PathElement::new(vec![(px, py), (px + 20, py)], RED));
        }
        legend!(chart, e, SeriesLabelPosition::UpperRight);
    });
    root.present().map_err(e)?;
    Ok(())
}

/// `v` with `digits` decimals for an axis label, without the sign of a value that rounds to
/// zero ("-0.00" where a grid line lies at a round-off below 0).
fn fixed(v: f64, digits: usize) -> String {
    let s = format!("{v:.digits$}");
    if s.starts_with('-') && s[1..].chars().all(|c| c == '0' || c == '.') {
        s[1..].to_string()
    } else {
        s
    }
}

#[cfg(test)]
mod tests {
    use super::with_a_decade;

    /// The legend goes where it covers no point: MiddleRight when that is free, elsewhere
    /// when a point sits there.
    #[test]
    fn a_regime_maps_legend_avoids_the_points() {
        use super::legend_place;
        use plotters::prelude::SeriesLabelPosition::*;
        let spread = [(0.1, 0.1), (0.1, 0.9), (0.5, 0.1), (0.5, 0.9)];
        assert!(matches!(legend_place(&spread, 4), (MiddleRight, 0)));
        let right_edge: Vec<_> = spread.iter().copied().chain([(0.95, 0.5)]).collect();
        let place = legend_place(&right_edge, 4);
        assert!(matches!(place, (UpperRight | LowerRight, 0)), "{place:?}");
        // Points everywhere: every place covers one.
        let grid: Vec<_> = (0..=10)
            .flat_map(|i| (0..=10).map(move |j| (0.1 * i as f64, 0.1 * j as f64)))
            .collect();
        assert!(legend_place(&grid, 4).1 > 0);
    }

    #[test]
    fn axis_labels_drop_the_sign_of_a_rounded_zero() {
        use super::fixed;
        assert_eq!(fixed(-1e-17, 2), "0.00");
        assert_eq!(fixed(-0.0, 3), "0.000");
        assert_eq!(fixed(-0.004, 2), "0.00");
        assert_eq!(fixed(-0.006, 2), "-0.01");
        assert_eq!(fixed(0.2, 2), "0.20");
        assert_eq!(fixed(-1.0, 2), "-1.00");
    }

    fn close(a: (f64, f64), b: (f64, f64)) -> bool {
        (a.0 / b.0 - 1.0).abs() < 1e-12 && (a.1 / b.1 - 1.0).abs() < 1e-12
    }

    #[test]
    fn log_ranges_hold_a_power_of_ten() {
        // Every run of a study costing the same: 1.07..6.5 s holds no power of ten.
        assert!(close(with_a_decade(1.07, 6.5), (1.0, 10.0)));
        assert!(close(with_a_decade(0.02, 0.09), (0.01, 0.1)));
        // Ranges that hold one are left alone.
        assert_eq!(with_a_decade(0.5, 20.0), (0.5, 20.0));
        assert_eq!(with_a_decade(1.0, 3.0), (1.0, 3.0));
        assert_eq!(with_a_decade(2e-3, 0.7), (2e-3, 0.7));
    }
}
