//! `report.md`: the page's content as Markdown, every caveat beside its number.

use super::caveats::{self, one_line};
use super::display;
use super::model::SequenceReport;
use super::page::{GLOSSARY, Summary, estimate_line};
use super::tables;

fn bullets(out: &mut String, items: &[String]) {
    for item in items {
        out.push_str(&format!("- ⚠ {}\n", one_line(item)));
    }
}

fn header(v: &Summary) -> String {
    let r = v.report;
    let mut out = format!(
        "# ctcal report\n\nctcal {} · `{}` · simulations seeded with {}. Everything below is also in `results.json`; tables in `tables/` (CSV, Parquet, LaTeX), plots in `plots/` (PNG, SVG, CSV), simulator configurations in `configs/`, hot-pixel masks in `masks/`.\n\n## Contents\n\n",
        r.ctcal_version,
        r.command_line.join(" "),
        r.seed
    );
    if !r.failed.is_empty() {
        out.push_str("- [Recordings that failed](#recordings-that-failed)\n");
    }
    out.push_str("- [Datasets](#datasets)\n- [Statistics](#statistics)\n- [Contrast thresholds](#contrast-thresholds)\n");
    for s in &r.sequences {
        out.push_str(&format!("- Sequence `{}`\n", s.name));
    }
    out.push_str("- [Glossary](#glossary)\n\n");
    if !r.failed.is_empty() {
        out.push_str(&format!(
            "## Recordings that failed\n\n{} of {} recordings could not be reported; everything below is of the others.\n\n",
            r.failed.len(),
            r.failed.len() + r.sequences.len()
        ));
        for f in &r.failed {
            out.push_str(&format!(
                "- **{}** (`{}`): {}\n",
                f.name,
                f.path,
                one_line(&f.error)
            ));
        }
        out.push('\n');
    }
    out
}

fn summary_tables(v: &Summary, out: &mut String) {
    let table = |name: &str| v.table(name).map(display::markdown).unwrap_or_default();
    out.push_str("## Datasets\n\n");
    out.push_str(&table("datasets"));
    out.push('\n');
    if let Some(t) = v.table("bias_sweep") {
        out.push_str(&format!("{}\n\n{}\n", t.caption, display::markdown(t)));
    }
    for plot in v.bias_plots {
        match plot {
            Ok(p) => out.push_str(&format!("\n![{}](plots/{}.png)\n\n", p.title, p.name)),
            Err(e) => bullets(out, &[format!("plot not drawn: {e}")]),
        }
    }
    for d in &v.report.datasets {
        let notes: Vec<String> = d
            .warnings
            .iter()
            .map(|w| format!("{}: {w}", d.name))
            .collect();
        bullets(out, &notes);
    }
    for path in v.combined_configs {
        out.push_str(&format!("- configuration `{path}`\n"));
    }
    match v.fig2 {
        Ok(p) => out.push_str(&format!("\n![{}](plots/{}.png)\n\n", p.title, p.name)),
        Err(e) => bullets(out, &[format!("plot not drawn: {e}")]),
    }
    out.push_str("## Statistics\n\n");
    out.push_str(&table("statistics"));
    out.push_str("\n## Contrast thresholds\n\n");
    out.push_str(&table("thresholds"));
}

fn fit_section(s: &SequenceReport, out: &mut String) {
    let Some(f) = &s.fit else {
        if let Some(why) = &s.fit_not_applied {
            out.push_str(&format!(
                "\n### Fitted model\n\nnot fitted: {}\n",
                one_line(why)
            ));
        }
        return;
    };
    let effects: Vec<&str> = f.effects_added.iter().map(|e| e.effect.name()).collect();
    out.push_str(&format!(
        "\n### Fitted model\n\nEffects added: **{}**. Held-out sim-to-real distance {} for the ideal model, {} for the fitted one.\n\n",
        if effects.is_empty() { "none".to_string() } else { effects.join(", ") },
        tables::number(f.error_before),
        tables::number(f.error_after)
    ));
    let one = [s];
    out.push_str(&display::markdown(&tables::fitted_parameters(&one)));
    out.push('\n');
    bullets(out, &caveats::of_fit(f));
    out.push_str("\n#### The loop\n\n");
    out.push_str(&display::markdown(&tables::fit_steps(&one)));
}

fn sequence(s: &SequenceReport, out: &mut String) {
    out.push_str(&format!(
        "\n## {}\n\ndataset {} · {} · sensor {} · {} events over {:.3} s",
        s.name,
        s.dataset,
        s.format,
        s.sensor(),
        s.stats.events,
        s.stats.duration_s
    ));
    if let Some(t) = &s.truth {
        out.push_str(&format!(" · true parameters from {}", t.source));
    }
    out.push_str("\n\n");
    bullets(out, &caveats::of_sequence(s));
    out.push_str("\n### Contrast thresholds\n\n");
    for m in &s.methods {
        match (&m.estimate, &m.not_applied) {
            (Some(e), _) => {
                out.push_str(&format!(
                    "**estimate {}**: {}\n\n",
                    m.method,
                    estimate_line(e)
                ));
                bullets(out, &caveats::of_estimate(e));
                out.push('\n');
            }
            (None, Some(why)) => out.push_str(&format!(
                "**estimate {}**: not applied: {}\n\n",
                m.method,
                one_line(why)
            )),
            (None, None) => {}
        }
    }
    fit_section(s, out);
    if !s.outputs.configs.is_empty() || !s.outputs.masks.is_empty() {
        let files: Vec<String> = s
            .outputs
            .configs
            .iter()
            .chain(&s.outputs.masks)
            .map(|p| format!("`{p}`"))
            .collect();
        out.push_str(&format!("\nFiles: {}.\n", files.join(", ")));
    }
    out.push('\n');
    for p in &s.outputs.plots {
        out.push_str(&format!("![{}](plots/{}.png)\n\n", p.title, p.name));
    }
}

/// `report.md`.
pub(super) fn render(v: &Summary) -> String {
    let mut out = header(v);
    summary_tables(v, &mut out);
    for s in &v.report.sequences {
        sequence(s, &mut out);
    }
    out.push_str("\n## Glossary\n\n");
    for (term, meaning) in GLOSSARY {
        out.push_str(&format!("- **{term}**: {meaning}\n"));
    }
    out
}
