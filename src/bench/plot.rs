//! Log-log work-precision diagrams (error against wall time), as SVG and PNG; the contact
//! report draws its overlap against cost on the same axes.

use super::work_precision::Row;
use crate::sim::Integrator;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

const SIZE: (u32, u32) = (960, 640);

/// Colours of the series that are not an integrator's own (variants with other settings).
const SPARE: [RGBColor; 4] = [
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(0, 0, 0),
];

fn colour(i: Integrator) -> RGBColor {
    match i {
        Integrator::ExplicitEuler => RGBColor(214, 39, 40),
        Integrator::SymplecticEuler => RGBColor(31, 119, 180),
        Integrator::VelocityVerlet => RGBColor(44, 160, 44),
        Integrator::Rk4 => RGBColor(148, 103, 189),
        Integrator::ImplicitEuler => RGBColor(255, 127, 14),
        Integrator::ProjectiveDynamics => RGBColor(23, 190, 207),
        Integrator::Xpbd => RGBColor(140, 86, 75),
        Integrator::Bdf2 => RGBColor(227, 119, 194),
        Integrator::Vbd => RGBColor(188, 189, 34),
    }
}

/// Writes `<stem>.svg` and `<stem>.png` for one scene's rows.
pub fn write_diagram(rows: &[&Row], title: &str, stem: &Path) -> Result<(), String> {
    write_diagram_with(
        rows,
        title,
        ("wall time (s)", "max position error (m)"),
        stem,
    )
}

/// [`write_diagram`] with other labels for the time and error axes.
pub fn write_diagram_with(
    rows: &[&Row],
    title: &str,
    labels: (&str, &str),
    stem: &Path,
) -> Result<(), String> {
    // The PNG's text is drawn by ab_glyph from egui's bundled font: no system fonts needed.
    let _ = plotters::style::register_font(
        "sans-serif",
        FontStyle::Normal,
        epaint_default_fonts::UBUNTU_LIGHT,
    );
    let svg = stem.with_extension("svg");
    let png = stem.with_extension("png");
    let svg_area = SVGBackend::new(&svg, SIZE).into_drawing_area();
    draw(svg_area, rows, title, labels)?;
    // Drawn into memory and encoded by the png crate (bevy's renderer uses it too), rather than
    // through plotters' own encoder, which brings a second, older `image` crate to the build.
    let mut rgb = vec![0u8; SIZE.0 as usize * SIZE.1 as usize * 3];
    draw(
        BitMapBackend::with_buffer(&mut rgb, SIZE).into_drawing_area(),
        rows,
        title,
        labels,
    )?;
    write_png(&png, &rgb, SIZE)
}

/// An 8-bit RGB image as a PNG file.
fn write_png(path: &Path, rgb: &[u8], (width, height): (u32, u32)) -> Result<(), String> {
    let fail = |e: &dyn std::fmt::Display| format!("cannot write {}: {e}", path.display());
    let file = std::fs::File::create(path).map_err(|e| fail(&e))?;
    let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().map_err(|e| fail(&e))?;
    writer.write_image_data(rgb).map_err(|e| fail(&e))?;
    writer.finish().map_err(|e| fail(&e))
}

fn draw<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    rows: &[&Row],
    title: &str,
    (x_label, y_label): (&str, &str),
) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    root.fill(&WHITE).map_err(e)?;
    let stable: Vec<&&Row> = rows.iter().filter(|r| r.stable && r.error > 0.0).collect();
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for r in rows.iter().filter(|r| r.wall_s > 0.0) {
        x0 = x0.min(r.wall_s);
        x1 = x1.max(r.wall_s);
    }
    for r in &stable {
        y0 = y0.min(r.error);
        y1 = y1.max(r.error);
    }
    if stable.is_empty() || x0 >= x1 {
        return Err(format!("{title}: nothing to plot"));
    }
    let (x0, x1) = (x0 / 1.5, x1 * 1.5);
    // Unstable runs sit on a band above the stable ones.
    let unstable_y = y1 * 20.0;
    let (y0, y1) = (y0 / 3.0, unstable_y * 3.0);
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 24))
        .margin(16)
        .x_label_area_size(48)
        .y_label_area_size(80)
        .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc(y_label)
        .x_label_formatter(&|v| format!("{v:.0e}"))
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .label_style(("sans-serif", 15))
        .draw()
        .map_err(e)?;
    // One series per label, in the order the rows name them; an integrator's own name gets
    // its colour, a variant (`implicit-euler ×10`) the next of the spare ones.
    let mut labels: Vec<&str> = vec![];
    for r in rows {
        if !labels.contains(&r.integrator.as_str()) {
            labels.push(&r.integrator);
        }
    }
    let mut spare = SPARE.iter().cycle();
    for label in labels {
        let c = Integrator::ALL
            .into_iter()
            .find(|i| i.cli_name() == label)
            .map(colour)
            .unwrap_or_else(|| *spare.next().unwrap_or(&BLACK));
        let mut mine: Vec<&&Row> = rows.iter().filter(|r| r.integrator == label).collect();
        mine.sort_by(|a, b| b.dt.total_cmp(&a.dt));
        let line: Vec<(f64, f64)> = mine
            .iter()
            .filter(|r| r.stable && r.error > 0.0 && r.wall_s > 0.0)
            .map(|r| (r.wall_s, r.error))
            .collect();
        chart
            .draw_series(LineSeries::new(line.clone(), c.stroke_width(2)))
            .map_err(e)?
            .label(label.to_string())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], c.stroke_width(3)));
        chart
            .draw_series(line.iter().map(|&p| Circle::new(p, 4, c.filled())))
            .map_err(e)?;
        let bad: Vec<(f64, f64)> = mine
            .iter()
            .filter(|r| !r.stable && r.wall_s > 0.0)
            .map(|r| (r.wall_s, unstable_y))
            .collect();
        chart
            .draw_series(bad.iter().map(|&p| Cross::new(p, 6, c.stroke_width(2))))
            .map_err(e)?;
    }
    chart
        .draw_series(std::iter::once(Text::new(
            "× unstable",
            (x0 * 1.05, unstable_y / 2.2),
            ("sans-serif", 15),
        )))
        .map_err(e)?;
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .label_font(("sans-serif", 15))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(e)?;
    root.present().map_err(e)?;
    Ok(())
}
