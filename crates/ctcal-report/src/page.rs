//! `index.html`: a table of contents, the summary tables (headers with units, empty columns
//! hidden), the recordings that failed, each sequence with every caveat beside the number
//! it qualifies, and a short glossary. Text is escaped here and handed to the template as
//! ready HTML.

use super::caveats;
use super::display::{escape_html, html as table_html};
use super::model::{PlotEntry, Report, SequenceReport};
use super::tables::{self, Table};
use crate::estimate::{CtEstimate, Interval};

/// What the summary pages (HTML and Markdown) are made of.
pub(super) struct Summary<'a> {
    pub report: &'a Report,
    pub tables: &'a [Table],
    pub fig2: &'a Result<PlotEntry, String>,
    /// Thresholds and noise against each bias that differs (none when nothing differs).
    pub bias_plots: &'a [Result<PlotEntry, String>],
    /// Configurations combined over datasets or sensors.
    pub combined_configs: &'a [String],
}

impl Summary<'_> {
    pub fn table(&self, name: &str) -> Option<&Table> {
        self.tables.iter().find(|t| t.name == name)
    }
}

/// The glossary shown on the page and in `report.md`: (term, meaning).
pub(super) const GLOSSARY: [(&str, &str); 5] = [
    (
        "evidence",
        "how far an effect lowers the held-out error, in standard errors of that error (over held-out time blocks); the fit keeps an effect only when its evidence clears the bar named in the step's reason",
    ),
    (
        "held-out error",
        "the sim-to-real distance between the recording and the simulation, measured only on time blocks the fit did not use, so that an effect cannot win by fitting noise",
    ),
    (
        "distance components",
        "the parts of the sim-to-real distance: counts (log ratio of events per intensity, rate of change and polarity), background (events no scene change explains), intervals (same-pixel interval histograms), polarity (ON/OFF balance), active (share of pixels with events), dispersion (how unevenly pixels fire) and, with frames, lag (how much later the recording's events come than the simulation's in some intensity bins than in others, in frame intervals); the total is their root sum of squares",
    ),
    (
        "95 % interval",
        "the range that holds the true value 95 times in 100 by the method's own error model, systematic errors included; an open side (–) means the value was extrapolated beyond what the method simulated",
    ),
    (
        "not determinable / not identified",
        "the recording does not fix this value: it is shown as – (JSON null) with the reason, never as a start value",
    ),
];

/// A value with its 95 % interval, or "not determinable".
pub(super) fn with_interval(v: Option<f64>, ci: Option<Interval>) -> String {
    let Some(v) = v else {
        return "not determinable".into();
    };
    let side = |s: Option<f64>| s.map_or("open".to_string(), tables::number);
    match ci {
        Some([lo, hi]) => format!("{} (95 %: {} to {})", tables::number(v), side(lo), side(hi)),
        None => tables::number(v),
    }
}

/// One line of an estimate: ON, OFF and their mean.
pub(super) fn estimate_line(e: &CtEstimate) -> String {
    format!(
        "ON {} · OFF {}",
        with_interval(e.ct_on, e.ct_on_ci95),
        with_interval(e.ct_off, e.ct_off_ci95)
    )
}

fn list(items: &[String], class: &str) -> String {
    if items.is_empty() {
        return String::new();
    }
    let mut out = format!("<ul class=\"{class}\">");
    for item in items {
        out.push_str(&format!(
            "<li>{}</li>",
            escape_html(&caveats::one_line(item))
        ));
    }
    out.push_str("</ul>\n");
    out
}

fn link(path: &str) -> String {
    let name = path.rsplit('/').next().unwrap_or(path);
    format!(
        "<a href=\"{}\">{}</a>",
        escape_html(path),
        escape_html(name)
    )
}

fn figure(p: &PlotEntry) -> String {
    let (name, title) = (escape_html(&p.name), escape_html(&p.title));
    format!(
        "<figure><img src=\"plots/{name}.png\" alt=\"{title}\"><figcaption>{title}. <a href=\"plots/{name}.svg\">SVG</a> &middot; <a href=\"plots/{name}.csv\">data</a></figcaption></figure>\n"
    )
}

/// The methods of a sequence, each with its caveats beneath it.
fn methods_html(s: &SequenceReport) -> String {
    let mut out = String::from("<h3>Contrast thresholds</h3>\n");
    for m in &s.methods {
        out.push_str(&format!("<h4>estimate {}</h4>\n", m.method));
        match (&m.estimate, &m.not_applied) {
            (Some(e), _) => {
                out.push_str(&format!("<p>{}</p>\n", escape_html(&estimate_line(e))));
                out.push_str(&list(&caveats::of_estimate(e), "caveats"));
            }
            (None, Some(why)) => out.push_str(&format!(
                "<p class=\"note\">not applied: {}</p>\n",
                escape_html(&caveats::one_line(why))
            )),
            (None, None) => {}
        }
    }
    out
}

/// The fit of a sequence: the outcome, parameters, caveats, the loop and configurations.
fn fit_html(s: &SequenceReport) -> String {
    let Some(f) = &s.fit else {
        return s.fit_not_applied.as_ref().map_or(String::new(), |why| {
            format!(
                "<h3>Fitted model</h3>\n<p class=\"note\">not fitted: {}</p>\n",
                escape_html(&caveats::one_line(why))
            )
        });
    };
    let one = [s];
    let effects = if f.effects_added.is_empty() {
        "none".to_string()
    } else {
        let names: Vec<&str> = f.effects_added.iter().map(|e| e.effect.name()).collect();
        names.join(", ")
    };
    let mut out = format!(
        "<h3>Fitted model</h3>\n<p>Effects added: <strong>{}</strong>. Held-out error (sim-to-real distance) {} for the ideal model, {} for the fitted one.</p>\n",
        escape_html(&effects),
        tables::number(f.error_before),
        tables::number(f.error_after)
    );
    out.push_str(&table_html(&tables::fitted_parameters(&one)));
    out.push_str(&list(&caveats::of_fit(f), "caveats"));
    out.push_str("<h4>The loop</h4>\n");
    out.push_str(&table_html(&tables::fit_steps(&one)));
    out
}

/// The files of a sequence: configurations and masks.
fn files_html(s: &SequenceReport) -> String {
    let mut out = String::new();
    if !s.outputs.configs.is_empty() {
        let links: Vec<String> = s.outputs.configs.iter().map(|p| link(p)).collect();
        out.push_str(&format!(
            "<p class=\"note\">Simulator configurations: {}</p>\n",
            links.join(" &middot; ")
        ));
    }
    if !s.outputs.masks.is_empty() {
        let links: Vec<String> = s.outputs.masks.iter().map(|p| link(p)).collect();
        out.push_str(&format!(
            "<p class=\"note\">Hot-pixel mask (0 = hot; give it as the pixel mask to leave the hot pixels out): {}</p>\n",
            links.join(" &middot; ")
        ));
    }
    out
}

/// One sequence's section.
fn sequence_html(s: &SequenceReport) -> String {
    let mut out = format!(
        "<h2 id=\"seq-{0}\">{0}</h2>\n<p class=\"note\">dataset {1} &middot; {2} &middot; sensor {3} &middot; {4} events over {5:.3} s",
        escape_html(&s.name),
        escape_html(&s.dataset),
        escape_html(&s.format),
        s.sensor(),
        s.stats.events,
        s.stats.duration_s
    );
    if let Some(t) = &s.truth {
        out.push_str(&format!(
            " &middot; true parameters from {}",
            escape_html(&t.source)
        ));
    }
    out.push_str("</p>\n");
    out.push_str(&list(&caveats::of_sequence(s), "caveats"));
    out.push_str(&methods_html(s));
    out.push_str(&fit_html(s));
    out.push_str(&files_html(s));
    for p in &s.outputs.plots {
        out.push_str(&figure(p));
    }
    out
}

/// The table of contents.
fn contents(report: &Report) -> String {
    let mut out = String::from("<nav id=\"contents\"><h2>Contents</h2><ol>\n");
    if !report.failed.is_empty() {
        out.push_str("<li><a href=\"#failed\">Recordings that failed</a></li>\n");
    }
    out.push_str("<li><a href=\"#datasets\">Datasets</a></li>\n<li><a href=\"#statistics\">Statistics</a></li>\n<li><a href=\"#thresholds\">Contrast thresholds</a></li>\n<li>Sequences<ol>\n");
    for s in &report.sequences {
        out.push_str(&format!(
            "<li><a href=\"#seq-{0}\">{0}</a></li>\n",
            escape_html(&s.name)
        ));
    }
    out.push_str("</ol></li>\n<li><a href=\"#glossary\">Glossary</a></li>\n</ol></nav>\n");
    out
}

fn failed_html(report: &Report) -> String {
    if report.failed.is_empty() {
        return String::new();
    }
    let mut out = format!(
        "<h2 id=\"failed\">Recordings that failed</h2>\n<p class=\"warn\">{} of {} recordings could not be reported; everything below is of the others.</p>\n<ul class=\"failed\">",
        report.failed.len(),
        report.failed.len() + report.sequences.len()
    );
    for f in &report.failed {
        out.push_str(&format!(
            "<li><strong>{}</strong> (<code>{}</code>): {}</li>",
            escape_html(&f.name),
            escape_html(&f.path),
            escape_html(&caveats::one_line(&f.error))
        ));
    }
    out.push_str("</ul>\n");
    out
}

fn datasets_html(v: &Summary) -> String {
    let mut out = v.table("datasets").map(table_html).unwrap_or_default();
    if let Some(t) = v.table("bias_sweep") {
        out.push_str(&format!(
            "<p class=\"note\">{}</p>\n",
            escape_html(t.caption)
        ));
        out.push_str(&table_html(t));
    }
    for plot in v.bias_plots {
        match plot {
            Ok(p) => out.push_str(&figure(p)),
            Err(e) => out.push_str(&list(&[format!("plot not drawn: {e}")], "caveats")),
        }
    }
    for d in &v.report.datasets {
        let notes: Vec<String> = d
            .warnings
            .iter()
            .map(|w| format!("{}: {w}", d.name))
            .collect();
        out.push_str(&list(&notes, "caveats"));
    }
    if !v.combined_configs.is_empty() {
        let links: Vec<String> = v.combined_configs.iter().map(|p| link(p)).collect();
        out.push_str(&format!(
            "<p class=\"note\">Configurations combined per dataset or sensor: {}</p>\n",
            links.join(" &middot; ")
        ));
    }
    match v.fig2 {
        Ok(p) => out.push_str(&figure(p)),
        Err(e) => out.push_str(&list(&[format!("plot not drawn: {e}")], "caveats")),
    }
    out
}

fn glossary_html() -> String {
    let mut out = String::from("<h2 id=\"glossary\">Glossary</h2>\n<dl>\n");
    for (term, meaning) in GLOSSARY {
        out.push_str(&format!(
            "<dt>{}</dt><dd>{}</dd>\n",
            escape_html(term),
            escape_html(meaning)
        ));
    }
    out.push_str("</dl>\n");
    out
}

/// `index.html`.
pub(super) fn html(v: &Summary) -> String {
    let r = v.report;
    let safe = minijinja::Value::from_safe_string;
    let table = |name: &str| safe(v.table(name).map(table_html).unwrap_or_default());
    let context = minijinja::context! {
        version => r.ctcal_version,
        command => r.command_line.join(" "),
        seed => r.seed,
        contents => safe(contents(r)),
        failed => safe(failed_html(r)),
        datasets => safe(datasets_html(v)),
        statistics_table => table("statistics"),
        thresholds_table => table("thresholds"),
        sequences => safe(r.sequences.iter().map(sequence_html).collect::<String>()),
        glossary => safe(glossary_html()),
    };
    let mut environment = minijinja::Environment::new();
    environment
        .add_template("index.html", include_str!("templates/index.html"))
        .expect("the template parses");
    environment
        .get_template("index.html")
        .and_then(|t| t.render(context))
        .expect("the template renders")
}
