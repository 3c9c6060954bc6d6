//! Reports and configurations: what `stats`, `estimate` and `fit` computed for a set of
//! recordings, rendered as a paper-style report (one model, [`model::Report`], and one
//! exporter per format, as hyperfine's `export` does):
//!
//! - `index.html` (self-contained: images by relative path, no network) and `report.md`;
//! - `results.json`: the whole model, with ctcal's version, the command line, the seed and
//!   every input's size and SHA-256;
//! - `tables/`: [`tables`] as CSV, Parquet, LaTeX (booktabs) and Markdown;
//! - `plots/`: [`plots`] as PNG and SVG with the CSV behind each;
//! - `configs/`: [`configs`] for every fitted sequence, and one generator configuration
//!   covering them all.
//!
//! Rendering returns files as bytes; the binary writes them (the library does no I/O).

pub mod configs;
pub mod model;
pub mod plots;
pub mod presets;
pub mod tables;

use model::{Report, SequenceReport};
use serde::Serialize;

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

/// The plot links a template shows.
#[derive(Serialize)]
struct PlotLink {
    title: String,
    png: String,
    svg: String,
    csv: String,
}

impl PlotLink {
    fn of(p: &plots::Plot) -> Self {
        Self {
            title: p.title.clone(),
            png: format!("plots/{}.png", p.name),
            svg: format!("plots/{}.svg", p.name),
            csv: format!("plots/{}.csv", p.name),
        }
    }
}

/// The configuration files of a sequence.
#[derive(Serialize)]
struct ConfigLink {
    name: String,
    path: String,
}

#[derive(Serialize)]
struct FitView {
    effects: String,
    metric_name: &'static str,
    before: String,
    after: String,
    parameters_table: minijinja::Value,
    steps_table: minijinja::Value,
}

#[derive(Serialize)]
struct SequenceView {
    name: String,
    dataset: String,
    format: String,
    sensor: String,
    events: u64,
    duration: String,
    truth: Option<String>,
    not_applied: Vec<String>,
    fit: Option<FitView>,
    configs: Vec<ConfigLink>,
    plots: Vec<PlotLink>,
}

/// An HTML table of a polars table (numbers right-aligned).
fn html_table(t: &tables::Table) -> minijinja::Value {
    let escape = |s: &str| {
        s.replace('&', "&amp;")
            .replace('<', "&lt;")
            .replace('>', "&gt;")
    };
    let columns = t.frame.columns();
    let mut out = String::from("<div class=\"wide\"><table>\n<tr>");
    for c in columns {
        out.push_str(&format!("<th>{}</th>", escape(c.name())));
    }
    out.push_str("</tr>\n");
    for i in 0..t.frame.height() {
        out.push_str("<tr>");
        for c in columns {
            let value = c.get(i).ok();
            let (text, numeric) = match value {
                Some(polars::prelude::AnyValue::Float64(v)) => (tables::number(v), true),
                Some(polars::prelude::AnyValue::Null) | None => ("–".to_string(), false),
                Some(v) => (v.to_string().trim_matches('"').to_string(), false),
            };
            out.push_str(&if numeric {
                format!("<td class=\"num\">{text}</td>")
            } else {
                format!("<td>{}</td>", escape(&text))
            });
        }
        out.push_str("</tr>\n");
    }
    out.push_str("</table></div>");
    minijinja::Value::from_safe_string(out)
}

/// The configuration files of one sequence's fit.
fn sequence_configs(s: &SequenceReport, seed: u64) -> Vec<OutputFile> {
    let Some(f) = &s.fit else { return Vec::new() };
    let exposure_ms = f.frame_exposure_us.map(|e| e as f64 / 1e3);
    [
        configs::ConfigFormat::Esim,
        configs::ConfigFormat::V2e,
        configs::ConfigFormat::Ctcal,
    ]
    .into_iter()
    .filter_map(|format| {
        configs::render(format, std::slice::from_ref(&f.params), exposure_ms, seed)
            .map(|text| file(format!("configs/{}/{}", s.name, format.file_name()), text))
    })
    .collect()
}

/// Every file of the report.
pub fn render(report: &Report) -> Vec<OutputFile> {
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
    for s in &report.sequences {
        for t in tables::of_sequence(s) {
            if t.frame.height() > 0 {
                files.push(file(
                    format!("tables/{}/{}.parquet", s.name, t.name),
                    tables::parquet(&t),
                ));
            }
        }
    }
    let mut failures = Vec::new();
    let mut rendered = Vec::new();
    for plot in plots::all(report) {
        match plot {
            Ok(p) => {
                files.push(file(format!("plots/{}.png", p.name), p.png.clone()));
                files.push(file(format!("plots/{}.svg", p.name), p.svg.clone()));
                files.push(file(format!("plots/{}.csv", p.name), p.csv.clone()));
                rendered.push(p);
            }
            Err(e) => failures.push(e),
        }
    }
    for s in &report.sequences {
        files.extend(sequence_configs(s, report.seed));
    }
    let fitted: Vec<crate::sim::PixelParams> = report
        .sequences
        .iter()
        .filter_map(|s| s.fit.as_ref().map(|f| f.params.model.clone()))
        .collect();
    if let Some(text) = configs::esim_generator(&fitted) {
        files.push(file("configs/esim_config_generator.json", text));
    }
    for d in &report.datasets {
        let members: Vec<crate::sim::PixelParams> = report
            .sequences
            .iter()
            .filter(|s| s.dataset == d.name)
            .filter_map(|s| s.fit.as_ref().map(|f| f.params.model.clone()))
            .collect();
        if members.len() > 1 {
            for format in configs::ConfigFormat::ALL {
                if let Some(text) = configs::render(format, &members, None, report.seed) {
                    files.push(file(
                        format!("configs/datasets/{}/{}", d.name, format.file_name()),
                        text,
                    ));
                }
            }
        }
    }
    let config_links = |s: &SequenceReport| -> Vec<ConfigLink> {
        files
            .iter()
            .filter(|f| f.path.starts_with(&format!("configs/{}/", s.name)))
            .map(|f| ConfigLink {
                name: f.path.rsplit('/').next().unwrap_or_default().to_string(),
                path: f.path.clone(),
            })
            .collect()
    };
    let views: Vec<SequenceView> = report
        .sequences
        .iter()
        .map(|s| sequence_view(s, &rendered, config_links(s)))
        .collect();
    let fig2 = rendered
        .iter()
        .find(|p| p.name == "events_per_pixel_per_second")
        .map(PlotLink::of);
    let find = |name: &str| all_tables.iter().find(|t| t.name == name).map(html_table);
    let context = minijinja::context! {
        version => report.ctcal_version,
        command => report.command_line.join(" "),
        seed => report.seed,
        datasets_table => find("datasets"),
        statistics_table => find("statistics"),
        thresholds_table => find("thresholds"),
        fig2 => minijinja::value::Serde(fig2),
        sequences => minijinja::value::Serde(views),
        failures => failures,
    };
    let mut environment = minijinja::Environment::new();
    environment
        .add_template("index.html", include_str!("templates/index.html"))
        .expect("the template parses");
    let html = environment
        .get_template("index.html")
        .and_then(|t| t.render(context))
        .expect("the template renders");
    files.push(file("index.html", html));
    files.push(file("report.md", markdown(report, &rendered, &all_tables)));
    files.push(file(
        "results.json",
        serde_json::to_string_pretty(report).expect("the report serialises") + "\n",
    ));
    files
}

fn sequence_view(
    s: &SequenceReport,
    rendered: &[plots::Plot],
    configs: Vec<ConfigLink>,
) -> SequenceView {
    let one = [s];
    let fit = s.fit.as_ref().map(|f| FitView {
        effects: if f.effects_added.is_empty() {
            "none".into()
        } else {
            f.effects_added
                .iter()
                .map(|e| e.effect.name())
                .collect::<Vec<_>>()
                .join(", ")
        },
        metric_name: "sim-to-real distance",
        before: tables::number(f.error_before),
        after: tables::number(f.error_after),
        parameters_table: html_table(&tables::fitted_parameters(&one)),
        steps_table: html_table(&tables::fit_steps(&one)),
    });
    let mut not_applied: Vec<String> = s
        .methods
        .iter()
        .filter_map(|m| {
            m.not_applied
                .as_ref()
                .map(|why| format!("estimate {}: {why}", m.method))
        })
        .collect();
    not_applied.extend(s.fit_not_applied.iter().map(|why| format!("fit: {why}")));
    SequenceView {
        name: s.name.clone(),
        dataset: s.dataset.clone(),
        format: s.format.clone(),
        sensor: format!("{}x{}", s.stats.width, s.stats.height),
        events: s.stats.events,
        duration: format!("{:.3} s", s.stats.duration_s),
        truth: s.truth.as_ref().map(|t| t.source.clone()),
        not_applied,
        fit,
        configs,
        plots: rendered
            .iter()
            .filter(|p| p.name.starts_with(&format!("{}/", s.name)))
            .map(PlotLink::of)
            .collect(),
    }
}

/// `report.md`.
fn markdown(report: &Report, rendered: &[plots::Plot], all: &[tables::Table]) -> String {
    let mut out = format!(
        "# ctcal report\n\nctcal {} · `{}` · simulations seeded with {}. Everything below is also in `results.json`; tables in `tables/` (CSV, Parquet, LaTeX), plots in `plots/` (PNG, SVG, CSV), simulator configurations in `configs/`.\n\n",
        report.ctcal_version,
        report.command_line.join(" "),
        report.seed
    );
    let table = |name: &str| {
        all.iter()
            .find(|t| t.name == name)
            .map(tables::markdown)
            .unwrap_or_default()
    };
    out.push_str("## Datasets\n\n");
    out.push_str(&table("datasets"));
    if let Some(p) = rendered
        .iter()
        .find(|p| p.name == "events_per_pixel_per_second")
    {
        out.push_str(&format!("\n![{}](plots/{}.png)\n\n", p.title, p.name));
    }
    out.push_str("## Statistics\n\n");
    out.push_str(&table("statistics"));
    out.push_str("\n## Contrast thresholds\n\n");
    out.push_str(&table("thresholds"));
    for s in &report.sequences {
        out.push_str(&format!(
            "\n## {}\n\ndataset {} · {} · {}x{} · {} events over {:.3} s",
            s.name,
            s.dataset,
            s.format,
            s.stats.width,
            s.stats.height,
            s.stats.events,
            s.stats.duration_s
        ));
        if let Some(t) = &s.truth {
            out.push_str(&format!(" · true parameters from {}", t.source));
        }
        out.push_str("\n\n");
        for m in &s.methods {
            if let Some(why) = &m.not_applied {
                out.push_str(&format!(
                    "- estimate {}: {}\n",
                    m.method,
                    why.replace('\n', " ")
                ));
            }
        }
        if let Some(why) = &s.fit_not_applied {
            out.push_str(&format!("- fit: {}\n", why.replace('\n', " ")));
        }
        if let Some(f) = &s.fit {
            let one = [s];
            out.push_str(&format!(
                "\n### Fitted model\n\nEffects added: **{}**. Held-out sim-to-real distance {} for the ideal model, {} for the fitted one.\n\n",
                if f.effects_added.is_empty() {
                    "none".to_string()
                } else {
                    f.effects_added.iter().map(|e| e.effect.name()).collect::<Vec<_>>().join(", ")
                },
                tables::number(f.error_before),
                tables::number(f.error_after)
            ));
            out.push_str(&tables::markdown(&tables::fitted_parameters(&one)));
            out.push_str("\n#### The loop\n\n");
            out.push_str(&tables::markdown(&tables::fit_steps(&one)));
            out.push_str(&format!(
                "\nConfigurations: `configs/{0}/esim.flagfile`, `configs/{0}/v2e_args.txt`, `configs/{0}/params.toml`.\n",
                s.name
            ));
        }
        out.push('\n');
        for p in rendered
            .iter()
            .filter(|p| p.name.starts_with(&format!("{}/", s.name)))
        {
            out.push_str(&format!("![{}](plots/{}.png)\n\n", p.title, p.name));
        }
    }
    out
}
