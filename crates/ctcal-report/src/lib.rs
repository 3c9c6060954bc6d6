//! # ctcal-report: the report of a set of recordings
//!
//! Reports and configurations: what `stats`, `estimate` and `fit` computed for a set of
//! recordings, rendered as a paper-style report (one model, [`model::Report`], and one
//! exporter per format, as hyperfine's `export` does):
//!
//! - `index.html` (self-contained: images by relative path, no network) and `report.md`,
//!   every caveat beside the number it qualifies;
//! - `results.json`: the whole model, with ctcal's version, the command line, the seed and
//!   every input's size and SHA-256, and the recordings that failed with their errors;
//! - `tables/`: [`tables`] as CSV, Parquet, LaTeX (booktabs) and Markdown;
//! - `plots/`: [`plots`] as PNG and SVG with the CSV behind each;
//! - `configs/`: [`configs`] for every fitted sequence, and per dataset and sensor;
//! - `masks/`: each sequence's hot-pixel mask ([`masks`]) as PNG and `.npy`.
//!
//! A sequence is rendered as soon as it is computed ([`render_sequence`]), so that its
//! per-pixel data can be dropped; the summary ([`render_summary`]) needs only the model.
//! Rendering returns files as bytes; the binary writes them (the library does no I/O).
//!
//! Arrows point down: this crate depends on `ctcal-core` alone (what it renders, and the
//! simulator its configurations and presets use); it reads no recording (the pipeline that
//! computes a report, `ctcal-pipeline`, reads them through `ctcal-io` and renders here).

pub mod bias_sweep;
pub mod caveats;
pub mod configs;
pub mod display;
pub mod grouping;
mod markdown;
pub mod masks;
pub mod model;
mod page;
pub mod plots;
pub mod presets;
pub mod tables;

// the core modules by their old paths (`crate::sim`, ...), as when this was a module of
// one crate
use ctcal_core::{estimate, fit, sim, stats};

use model::{PixelData, PlotEntry, Report, SequenceReport};

/// A file of the rendered report: its path inside the report folder and its bytes.
pub struct OutputFile {
    pub path: String,
    pub bytes: Vec<u8>,
}

fn file(path: impl Into<String>, bytes: impl Into<Vec<u8>>) -> OutputFile {
    OutputFile {
        path: path.into(),
        bytes: bytes.into(),
    }
}

/// The three files of a plot.
fn plot_files(p: &plots::Plot) -> [OutputFile; 3] {
    [
        file(format!("plots/{}.png", p.name), p.png.clone()),
        file(format!("plots/{}.svg", p.name), p.svg.clone()),
        file(format!("plots/{}.csv", p.name), p.csv.clone()),
    ]
}

/// Every file of one sequence (its tables as Parquet, plots, configurations and hot-pixel
/// mask), recording in `s.outputs` what was written: after this, `pixels` may be dropped.
pub fn render_sequence(s: &mut SequenceReport, pixels: &PixelData, seed: u64) -> Vec<OutputFile> {
    let mut files: Vec<OutputFile> = tables::of_sequence(s)
        .iter()
        .filter(|t| t.frame.height() > 0)
        .map(|t| {
            file(
                format!("tables/{}/{}.parquet", s.name, t.name),
                tables::parquet(t),
            )
        })
        .collect();
    for plot in plots::sequence(s, pixels) {
        match plot {
            Ok(p) => {
                files.extend(plot_files(&p));
                s.outputs.plots.push(PlotEntry {
                    name: p.name,
                    title: p.title,
                });
            }
            Err(e) => s.outputs.plots_not_drawn.push(e),
        }
    }
    let configs = configs::files::of_sequence(s, seed);
    s.outputs.configs = configs.iter().map(|(path, _)| path.clone()).collect();
    files.extend(configs.into_iter().map(|(path, text)| file(path, text)));
    let (w, h) = (s.stats.width as usize, s.stats.height as usize);
    if w * h > 0 {
        let stem = format!("masks/{}/hot_pixels", s.name);
        files.push(file(
            format!("{stem}.png"),
            masks::png(w, h, &s.stats.hot_pixels),
        ));
        files.push(file(
            format!("{stem}.npy"),
            masks::npy(w, h, &s.stats.hot_pixels),
        ));
        s.outputs.masks = vec![format!("{stem}.png"), format!("{stem}.npy")];
    }
    files
}

/// The files of the whole report, once every sequence was rendered: the summary tables,
/// Fig. 2, the configurations per dataset and sensor, `index.html`, `report.md` and
/// `results.json`.
pub fn render_summary(report: &Report) -> Vec<OutputFile> {
    let mut files = Vec::new();
    let all_tables = tables::all(report);
    for t in &all_tables {
        files.push(file(format!("tables/{}.csv", t.name), tables::csv(t)));
        files.push(file(
            format!("tables/{}.parquet", t.name),
            tables::parquet(t),
        ));
        files.push(file(format!("tables/{}.tex", t.name), tables::latex(t)));
        files.push(file(format!("tables/{}.md", t.name), tables::markdown(t)));
    }
    let fig2 = plots::fig2(report);
    if let Ok(p) = &fig2 {
        files.extend(plot_files(p));
    }
    let entry = |p: plots::Plot| PlotEntry {
        name: p.name,
        title: p.title,
    };
    let fig2 = fig2.map(entry);
    let bias_plots: Vec<Result<PlotEntry, String>> = plots::bias_sweeps(report)
        .into_iter()
        .map(|p| {
            if let Ok(p) = &p {
                files.extend(plot_files(p));
            }
            p.map(entry)
        })
        .collect();
    let combined = configs::files::combined(report);
    let combined_paths: Vec<String> = combined.iter().map(|(p, _)| p.clone()).collect();
    files.extend(combined.into_iter().map(|(path, text)| file(path, text)));
    let view = page::Summary {
        report,
        tables: &all_tables,
        fig2: &fig2,
        bias_plots: &bias_plots,
        combined_configs: &combined_paths,
    };
    files.push(file("index.html", page::html(&view)));
    files.push(file("report.md", markdown::render(&view)));
    files.push(file(
        "results.json",
        serde_json::to_string_pretty(report).expect("the report serialises") + "\n",
    ));
    files
}
