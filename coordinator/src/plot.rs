//! PNG plots with a font shipped in the binary (no system font lookup).
use plotters::prelude::*;
use std::path::Path;
use std::sync::Once;

static FONT: Once = Once::new();

fn register_font() {
    FONT.call_once(|| {
        let bytes: &'static [u8] = include_bytes!("../assets/DejaVuSans.ttf");
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, bytes);
    });
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
    let (x0, x1) = (x0 / 1.5, x1 * 4.0);
    let (y0, y1) = (y0 / 3.0, y1 * 3.0);
    let e = |e: DrawingAreaErrorKind<_>| format!("plotting {}: {e:?}", path.display());
    let root = BitMapBackend::new(path, (900, 600)).into_drawing_area();
    root.fill(&WHITE).map_err(e)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 22))
        .margin(20)
        .x_label_area_size(50)
        .y_label_area_size(80)
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
