//! Top-down picture of a run: the head's path and the snake's (or robot's) pose at regular moments.

use std::path::Path;
use std::sync::OnceLock;

use anyhow::{anyhow, Result};
use image::codecs::png::{CompressionType, FilterType, PngEncoder};
use image::{ColorType, ImageEncoder};
use plotters::prelude::*;
use plotters::style::FontStyle;
use snake_core::{Pose, Simulation};

use crate::output::OutputFile;

/// Fonts to label the plot with, the first that exists wins (Debian's fonts-dejavu-core first).
const FONT_CANDIDATES: &[&str] = &[
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
    "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
];

/// Registers a system font with plotters once; false when none is installed (the plot then has no text).
fn font_available() -> bool {
    static FONT: OnceLock<bool> = OnceLock::new();
    *FONT.get_or_init(|| {
        FONT_CANDIDATES.iter().any(|path| {
            std::fs::read(path)
                .ok()
                .map(|bytes| {
                    let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
                    plotters::style::register_font("sans-serif", FontStyle::Normal, bytes).is_ok()
                })
                .unwrap_or(false)
        })
    })
}

/// Checks a plot's path before the run (a PNG file in a writable directory); the plot is drawn into
/// the returned file.
pub fn output(path: &Path) -> Result<OutputFile> {
    OutputFile::new(path, "plot", &["png"])
}

/// The plot's side in pixels unless `--plot-size` says otherwise.
pub const DEFAULT_SIZE: u32 = 900;
/// Smallest side: below it the labels overlap the drawing.
pub const MIN_SIZE: u32 = 200;
/// Largest side (a 4000 x 4000 RGB image is 48 MB in memory).
pub const MAX_SIZE: u32 = 4000;

/// What a run leaves to draw.
pub struct PathPlot {
    trace: Vec<(f64, f64)>,
    snapshots: Vec<(f64, Vec<Pose>)>,
    half_extent: f64,
    /// The world's water, `[x_min, y_min, x_max, y_max]` each, shaded where the drawing reaches it.
    water: Vec<[f64; 4]>,
}

impl PathPlot {
    /// An empty plot whose bodies are drawn as squares of `half_extent` (metres).
    pub fn new(half_extent: f64) -> Self {
        PathPlot {
            trace: Vec::new(),
            snapshots: Vec::with_capacity(10),
            half_extent,
            water: Vec::new(),
        }
    }

    /// Shades these water areas (`[x_min, y_min, x_max, y_max]`, metres) under the path.
    pub fn with_water(mut self, areas: Vec<[f64; 4]>) -> Self {
        self.water = areas;
        self
    }

    /// Adds the head's (the base's) current position to the path.
    pub fn trace(&mut self, body: &dyn Simulation) -> Result<()> {
        let p = body.base_state()?.pose.position;
        self.trace.push((p.x, p.y));
        Ok(())
    }

    /// Records the pose of every body part (cube or link) now.
    pub fn sample(&mut self, body: &dyn Simulation) -> Result<()> {
        self.trace(body)?;
        self.snapshots.push((body.time(), body.body_poses()?));
        Ok(())
    }

    /// Draws the PNG, `size` pixels square, and puts it in place.
    pub fn draw(&self, file: OutputFile, title: &str, size: u32) -> Result<()> {
        let path = file.path();
        let h = self.half_extent;
        let points = self
            .snapshots
            .iter()
            .flat_map(|(_, poses)| poses.iter().map(|p| (p.position.x, p.position.y)))
            .chain(self.trace.iter().copied());
        let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for (x, y) in points {
            x0 = x0.min(x);
            x1 = x1.max(x);
            y0 = y0.min(y);
            y1 = y1.max(y);
        }
        // Equal scales on both axes, so that the snake keeps its shape.
        let span = (x1 - x0).max(y1 - y0) + 4.0 * h;
        let (cx, cy) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
        let (xr, yr) = (
            cx - span / 2.0..cx + span / 2.0,
            cy - span / 2.0..cy + span / 2.0,
        );

        let err = |e: &dyn std::fmt::Display| anyhow!("cannot draw plot {}: {e}", path.display());
        // Drawn into memory and encoded here: plotters' own PNG writer uses fast compression, which
        // leaves the atlas's pictures three times larger than the best compression does.
        let mut pixels = vec![0u8; 3 * size as usize * size as usize];
        let root = BitMapBackend::with_buffer(&mut pixels, (size, size)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| err(&e))?;
        let text = font_available();
        let mut builder = ChartBuilder::on(&root);
        builder.margin(20);
        if text {
            builder
                .caption(title, ("sans-serif", 24))
                .x_label_area_size(40)
                .y_label_area_size(60);
        }
        let mut chart = builder.build_cartesian_2d(xr, yr).map_err(|e| err(&e))?;
        if text {
            chart
                .configure_mesh()
                .x_desc("x [m]")
                .y_desc("y [m]")
                .light_line_style(RGBColor(235, 235, 235))
                .draw()
                .map_err(|e| err(&e))?;
        }
        // Water under everything, clipped to the drawing (a pool may reach far beyond the path).
        let water = RGBColor(170, 205, 240);
        for (k, [wx0, wy0, wx1, wy1]) in self.water.iter().enumerate() {
            let (ax0, ax1) = (wx0.max(cx - span / 2.0), wx1.min(cx + span / 2.0));
            let (ay0, ay1) = (wy0.max(cy - span / 2.0), wy1.min(cy + span / 2.0));
            if ax0 >= ax1 || ay0 >= ay1 {
                continue;
            }
            let area = chart
                .draw_series(std::iter::once(Rectangle::new(
                    [(ax0, ay0), (ax1, ay1)],
                    water.mix(0.6).filled(),
                )))
                .map_err(|e| err(&e))?;
            if text && k == 0 {
                area.label("water").legend(move |(x, y)| {
                    Rectangle::new([(x + 3, y - 5), (x + 13, y + 5)], water.filled())
                });
            }
        }
        let path_series = chart
            .draw_series(LineSeries::new(
                self.trace.iter().copied(),
                BLUE.mix(0.6).stroke_width(2),
            ))
            .map_err(|e| err(&e))?;
        if text {
            path_series.label("head's path").legend(|(x, y)| {
                PathElement::new(vec![(x, y), (x + 16, y)], BLUE.mix(0.6).stroke_width(2))
            });
        }

        let n = self.snapshots.len().max(2) as f64;
        for (k, (t, poses)) in self.snapshots.iter().enumerate() {
            // Early poses pale, late poses dark.
            let shade = 0.25 + 0.75 * k as f64 / (n - 1.0);
            for (i, pose) in poses.iter().enumerate() {
                let colour = if i == 0 {
                    RED.mix(shade)
                } else {
                    BLACK.mix(shade * 0.8)
                };
                let corners = square(pose, h);
                let cube = chart
                    .draw_series(std::iter::once(Polygon::new(
                        corners.clone(),
                        colour.mix(0.35).filled(),
                    )))
                    .map_err(|e| err(&e))?;
                // The legend names the last moment's head and one body cube (earlier ones are paler).
                if text && k + 1 == self.snapshots.len() && i <= 1 {
                    let (label, swatch) = if i == 0 {
                        ("head (its time beside it)", RED.mix(0.5))
                    } else {
                        ("body, pale early to dark late", BLACK.mix(0.4))
                    };
                    cube.label(label).legend(move |(x, y)| {
                        Rectangle::new([(x + 3, y - 5), (x + 13, y + 5)], swatch.filled())
                    });
                }
                let mut outline = corners;
                outline.push(outline[0]);
                chart
                    .draw_series(std::iter::once(PathElement::new(
                        outline,
                        colour.stroke_width(1),
                    )))
                    .map_err(|e| err(&e))?;
            }
            if text {
                let head = &poses[0].position;
                chart
                    .draw_series(std::iter::once(Text::new(
                        format!("{t:.1} s"),
                        (head.x + 1.2 * h, head.y),
                        ("sans-serif", 14),
                    )))
                    .map_err(|e| err(&e))?;
            }
        }
        if text {
            // The legend goes in the corner the drawing leaves emptiest (a corner's band: half the
            // width, the outer quarter of the height), so that it covers as little of it as can be.
            let points: Vec<(f64, f64)> = self
                .snapshots
                .iter()
                .flat_map(|(_, poses)| poses.iter().map(|p| (p.position.x, p.position.y)))
                .chain(self.trace.iter().copied())
                .collect();
            let in_corner = |right: bool, top: bool| {
                points
                    .iter()
                    .filter(|&&(x, y)| {
                        (x > cx) == right
                            && if top {
                                y > cy + span / 4.0
                            } else {
                                y < cy - span / 4.0
                            }
                    })
                    .count()
            };
            let corners = [
                (SeriesLabelPosition::UpperRight, in_corner(true, true)),
                (SeriesLabelPosition::UpperLeft, in_corner(false, true)),
                (SeriesLabelPosition::LowerRight, in_corner(true, false)),
                (SeriesLabelPosition::LowerLeft, in_corner(false, false)),
            ];
            let (corner, _) = corners
                .into_iter()
                .min_by_key(|&(_, count)| count)
                .expect("four corners");
            chart
                .configure_series_labels()
                .position(corner)
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK.mix(0.4))
                .label_font(("sans-serif", (size / 64).clamp(10, 14)))
                .draw()
                .map_err(|e| err(&e))?;
        }
        root.present().map_err(|e| err(&e))?;
        drop(chart);
        drop(root);
        let out = std::fs::File::create(file.temp_path()).map_err(|e| err(&e))?;
        PngEncoder::new_with_quality(
            std::io::BufWriter::new(out),
            CompressionType::Best,
            FilterType::Adaptive,
        )
        .write_image(&pixels, size, size, ColorType::Rgb8)
        .map_err(|e| err(&e))?;
        file.commit()
    }
}

/// The four corners of a cube's footprint, seen from above.
fn square(pose: &Pose, h: f64) -> Vec<(f64, f64)> {
    let yaw = pose.yaw();
    let (s, c) = yaw.sin_cos();
    [(-h, -h), (h, -h), (h, h), (-h, h)]
        .iter()
        .map(|&(dx, dy)| {
            (
                pose.position.x + c * dx - s * dy,
                pose.position.y + s * dx + c * dy,
            )
        })
        .collect()
}
