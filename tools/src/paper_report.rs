//! The report of `spu paper`: the tables' rows filled in from the jobs' statistics, as
//! typed data (report.json), as Markdown and HTML pages, and as `results.md`: the tables
//! side by side with the paper's, with nothing of the host in them, so that the copy
//! committed as `docs/results.md` can be compared byte for byte with what the code
//! produces (`scripts/check-results`).

use crate::paper_jobs::Job;
use crate::paper_tables::{value, Measured, TableSpec};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::fmt::Write;

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Report {
    /// Width and height of every frame.
    pub size: u32,
    pub scenes: Vec<ReportScene>,
    pub tables: Vec<Table>,
    pub figures: Vec<Figure>,
    /// Jobs planned, and how many of them have statistics.
    pub jobs: usize,
    pub jobs_measured: usize,
    /// Stats files that were missing or unreadable, with the reason.
    pub missing: Vec<String>,
    /// Per scene: its cycles and DMA-wait heat maps (paths relative to the report).
    #[serde(default)]
    pub heatmaps: Vec<HeatMaps>,
    pub notes: Vec<String>,
    /// "Beyond the paper": a verdict on each of the paper's predictions, written from the
    /// measured numbers (`paper_beyond::verdicts`).
    #[serde(default)]
    pub verdicts: Vec<String>,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct HeatMaps {
    pub scene: String,
    pub config: String,
    pub cycles: String,
    pub wait: String,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ReportScene {
    pub id: String,
    pub source: String,
    /// The paper's scene it stands in for.
    pub paper: String,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Table {
    pub id: String,
    pub title: String,
    pub unit: String,
    pub note: String,
    pub rows: Vec<Row>,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Row {
    pub label: String,
    pub scene: String,
    pub paper_scene: String,
    pub paper: Option<f64>,
    pub ours: Option<f64>,
    /// Ours over the paper's.
    pub ratio: Option<f64>,
    /// The runs our number comes from.
    pub config: String,
    /// Why there is no number of ours.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub missing: Option<String>,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Figure {
    pub id: String,
    pub title: String,
    /// Files next to the report.
    pub files: Vec<String>,
}

/// Fills the tables in from the statistics by job name (`Err`: why a job has none).
pub fn build(
    specs: &[TableSpec],
    results: &BTreeMap<String, Result<Measured, String>>,
) -> Vec<Table> {
    specs
        .iter()
        .map(|spec| Table {
            id: spec.id.into(),
            title: spec.title.into(),
            unit: spec.unit.into(),
            note: spec.note.clone(),
            rows: spec
                .rows
                .iter()
                .map(|row| {
                    let (ours, config, missing) = match &row.jobs {
                        Err(why) => (None, String::new(), Some(why.clone())),
                        Ok(jobs) => {
                            let config = describe_jobs(jobs);
                            let found: Result<Vec<&Measured>, String> = jobs
                                .iter()
                                .map(|j| match results.get(&j.name()) {
                                    Some(Ok(m)) => Ok(m),
                                    Some(Err(e)) => Err(e.clone()),
                                    None => Err(format!("{}: not run", j.name())),
                                })
                                .collect();
                            match found.and_then(|m| value(row.metric, &m)) {
                                Ok(v) if v.is_finite() => (Some(v), config, None),
                                Ok(_) => (None, config, Some("not a number".into())),
                                Err(e) => (None, config, Some(e)),
                            }
                        }
                    };
                    let ratio = match (ours, row.paper) {
                        (Some(o), Some(p)) if p != 0.0 => Some(o / p),
                        _ => None,
                    };
                    Row {
                        label: row.label.clone(),
                        scene: row.scene.id.clone(),
                        paper_scene: row.scene.paper.name().into(),
                        paper: row.paper,
                        ours,
                        ratio,
                        config,
                        missing,
                    }
                })
                .collect(),
        })
        .collect()
}

fn describe_jobs(jobs: &[Job]) -> String {
    match jobs {
        [one] => one.describe(),
        [a, b] => {
            // the second run as it differs from the first
            let first = a.describe();
            let second = b.describe();
            let shared: Vec<&str> = first.split(", ").collect();
            let differs: Vec<&str> = second
                .split(", ")
                .filter(|part| !shared.contains(part))
                .collect();
            format!("{first} vs {}", differs.join(", "))
        }
        _ => jobs.iter().map(Job::name).collect::<Vec<_>>().join(", "),
    }
}

/// A number as the tables print it: up to three significant decimals.
pub fn fmt_num(x: Option<f64>) -> String {
    match x {
        None => "–".into(),
        Some(v) if v.abs() >= 100.0 => format!("{v:.1}"),
        Some(v) if v.abs() >= 10.0 => format!("{v:.2}"),
        Some(v) => format!("{v:.3}"),
    }
}

fn fmt_ratio(x: Option<f64>) -> String {
    x.map_or("–".into(), |r| format!("{r:.2}"))
}

impl Report {
    pub fn to_markdown(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(
            s,
            "# Ray Tracing on the Cell Processor (Benthin et al. 2006): the paper's numbers and ours\n"
        );
        let _ = writeln!(
            s,
            "Measured by `spu paper` on the simulator at {0}x{0} pixels; {1} of {2} runs measured.\n",
            self.size, self.jobs_measured, self.jobs
        );
        let _ = writeln!(s, "| scene | source | stands in for |\n|---|---|---|");
        for sc in &self.scenes {
            let _ = writeln!(s, "| {} | {} | {} |", sc.id, sc.source, sc.paper);
        }
        if !self.notes.is_empty() || !self.missing.is_empty() {
            let _ = writeln!(s);
            for n in &self.notes {
                let _ = writeln!(s, "- {n}");
            }
            for m in &self.missing {
                let _ = writeln!(s, "- missing: {m}");
            }
        }
        if !self.heatmaps.is_empty() {
            let _ = writeln!(
                s,
                "\n## Heat maps\n\nSimulated cycles per 8x8 packet, and the share of them spent waiting on DMA."
            );
            for h in &self.heatmaps {
                let _ = writeln!(
                    s,
                    "\n{} ({}):\n\n![{} cycles]({}) ![{} DMA waits]({})",
                    h.scene, h.config, h.scene, h.cycles, h.scene, h.wait
                );
            }
        }
        for t in &self.tables {
            let _ = writeln!(s, "\n## {}\n\n{}", t.title, t.note);
            if !t.unit.is_empty() {
                let _ = writeln!(s, "Unit: {}.", t.unit);
            }
            if let Some(f) = self.figures.iter().find(|f| f.id == t.id) {
                for file in f.files.iter().filter(|f| f.ends_with(".svg")) {
                    let _ = writeln!(s, "\n![{}]({file})", f.title);
                }
            }
            let _ = writeln!(
                s,
                "\n| row | scene (paper's) | paper | ours | ours/paper | configuration |\n|---|---|---:|---:|---:|---|"
            );
            for r in &t.rows {
                let config = match &r.missing {
                    Some(why) => format!("**not measured**: {why}"),
                    None => r.config.clone(),
                };
                let _ = writeln!(
                    s,
                    "| {} | {} ({}) | {} | {} | {} | {} |",
                    r.label,
                    r.scene,
                    r.paper_scene,
                    fmt_num(r.paper),
                    fmt_num(r.ours),
                    fmt_ratio(r.ratio),
                    config.replace('|', "\\|")
                );
            }
        }
        s + &self.verdicts_markdown()
    }

    /// The verdicts on the paper's predictions, as a Markdown section (empty without any).
    fn verdicts_markdown(&self) -> String {
        let mut s = String::new();
        if !self.verdicts.is_empty() {
            let _ = writeln!(
                s,
                "\n## Beyond the paper: its proposals measured, a verdict on each\n"
            );
            for v in &self.verdicts {
                let _ = writeln!(s, "- {v}");
            }
        }
        s
    }

    /// The tables laid out as the paper's: a row per label, for each scene the paper's
    /// number beside ours. Only simulated figures and the paper's go in (no host times,
    /// dates, paths or heat maps), so the same code gives the same bytes on any host.
    pub fn to_results_markdown(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(
            s,
            "# Ray Tracing on the Cell Processor (Benthin et al. 2006): the paper's numbers and ours\n"
        );
        let _ = writeln!(
            s,
            "Written by `spu paper` as `results.md` in its `--out` directory (beside `report.md`, which adds each row's ratio to the paper's, heat maps and Figure 2's plot). The copy in `docs/results.md` is the full run, `spu paper --scenes room,conference,beetle`, and `scripts/check-results` fails when it differs from what the code produces.\n"
        );
        let scenes: Vec<String> = self
            .scenes
            .iter()
            .map(|sc| format!("{} (for the paper's {})", sc.id, sc.paper))
            .collect();
        let _ = writeln!(
            s,
            "Frames of {0}x{0} pixels; scenes: {1}; {2} of {3} runs measured. Every number of ours is the simulator's (cycles and counters, the same for any host and any `--threads`).",
            self.size,
            scenes.join(", "),
            self.jobs_measured,
            self.jobs
        );
        if !self.notes.is_empty() || !self.missing.is_empty() {
            let _ = writeln!(s);
            for n in &self.notes {
                let _ = writeln!(s, "- {n}");
            }
            for m in &self.missing {
                let _ = writeln!(s, "- missing: {m}");
            }
        }
        for t in &self.tables {
            let _ = writeln!(s, "\n## {}\n\n{}", t.title, t.note);
            if !t.unit.is_empty() {
                let _ = writeln!(s, "Unit: {}.", t.unit);
            }
            // the labels in their first order, and for each the rows by scene
            let mut labels: Vec<&str> = Vec::new();
            for r in &t.rows {
                if !labels.contains(&r.label.as_str()) {
                    labels.push(&r.label);
                }
            }
            let _ = write!(s, "\n| row |");
            for sc in &self.scenes {
                let _ = write!(s, " {} (paper) | {} |", sc.paper, sc.id);
            }
            let _ = write!(s, " runs (ours) |\n|---|");
            for _ in &self.scenes {
                s.push_str("---:|---:|");
            }
            s.push_str("---|\n");
            let mut unmeasured = Vec::new();
            for label in &labels {
                let rows: Vec<&Row> = t.rows.iter().filter(|r| r.label == *label).collect();
                let _ = write!(s, "| {label} |");
                for sc in &self.scenes {
                    match rows.iter().find(|r| r.scene == sc.id) {
                        Some(r) => {
                            let _ = write!(s, " {} | {} |", fmt_num(r.paper), fmt_num(r.ours));
                            if let Some(why) = &r.missing {
                                unmeasured.push(format!("{label}, {}: {why}", sc.id));
                            }
                        }
                        None => s.push_str(" – | – |"),
                    }
                }
                // the runs differ between scenes only in the scene, which is the column
                let config = rows
                    .iter()
                    .find(|r| r.missing.is_none())
                    .map_or("", |r| r.config.as_str());
                let _ = writeln!(s, " {} |", config.replace('|', "\\|"));
            }
            if !unmeasured.is_empty() {
                let _ = writeln!(s, "\nNot measured:");
                for u in unmeasured {
                    let _ = writeln!(s, "- {u}");
                }
            }
        }
        s + &self.verdicts_markdown()
    }

    pub fn to_html(&self) -> String {
        let e = html_escape;
        let mut s = String::from(
            "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>spu paper report</title>\n<style>body{font-family:sans-serif;max-width:75em;margin:auto}table{border-collapse:collapse;margin-bottom:1em}td,th{border:1px solid #bbb;padding:2px 6px}td.n{text-align:right}tr.missing td{color:#888}</style></head><body>\n",
        );
        let _ = writeln!(
            s,
            "<h1>Ray Tracing on the Cell Processor (Benthin et al. 2006): the paper's numbers and ours</h1>\n<p>Measured by <code>spu paper</code> on the simulator at {0}x{0} pixels; {1} of {2} runs measured.</p>",
            self.size, self.jobs_measured, self.jobs
        );
        let _ = writeln!(
            s,
            "<table><tr><th>scene</th><th>source</th><th>stands in for</th></tr>"
        );
        for sc in &self.scenes {
            let _ = writeln!(
                s,
                "<tr><td>{}</td><td>{}</td><td>{}</td></tr>",
                e(&sc.id),
                e(&sc.source),
                e(&sc.paper)
            );
        }
        s.push_str("</table>\n<ul>\n");
        for n in &self.notes {
            let _ = writeln!(s, "<li>{}</li>", e(n));
        }
        for m in &self.missing {
            let _ = writeln!(s, "<li>missing: {}</li>", e(m));
        }
        s.push_str("</ul>\n");
        for t in &self.tables {
            let _ = writeln!(
                s,
                "<h2 id=\"{}\">{}</h2>\n<p>{}{}</p>",
                e(&t.id),
                e(&t.title),
                e(&t.note),
                if t.unit.is_empty() {
                    String::new()
                } else {
                    format!(" Unit: {}.", e(&t.unit))
                }
            );
            if let Some(f) = self.figures.iter().find(|f| f.id == t.id) {
                for file in f.files.iter().filter(|f| f.ends_with(".svg")) {
                    let _ = writeln!(
                        s,
                        "<p><img src=\"{}\" alt=\"{}\"></p>",
                        e(file),
                        e(&f.title)
                    );
                }
            }
            s.push_str("<table><tr><th>row</th><th>scene (paper's)</th><th>paper</th><th>ours</th><th>ours/paper</th><th>configuration</th></tr>\n");
            for r in &t.rows {
                let (class, config) = match &r.missing {
                    Some(why) => (" class=\"missing\"", format!("not measured: {why}")),
                    None => ("", r.config.clone()),
                };
                let _ = writeln!(
                    s,
                    "<tr{class}><td>{}</td><td>{} ({})</td><td class=\"n\">{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td><td>{}</td></tr>",
                    e(&r.label),
                    e(&r.scene),
                    e(&r.paper_scene),
                    fmt_num(r.paper),
                    fmt_num(r.ours),
                    fmt_ratio(r.ratio),
                    e(&config)
                );
            }
            s.push_str("</table>\n");
        }
        if !self.heatmaps.is_empty() {
            s.push_str("<h2 id=\"heatmaps\">Heat maps</h2>\n<p>Simulated cycles per 8x8 packet, and the share of them spent waiting on DMA.</p>\n");
            for h in &self.heatmaps {
                let _ = writeln!(
                    s,
                    "<p>{} ({})<br><img src=\"{}\" alt=\"cycles\"> <img src=\"{}\" alt=\"DMA waits\"></p>",
                    e(&h.scene),
                    e(&h.config),
                    e(&h.cycles),
                    e(&h.wait)
                );
            }
        }
        if !self.verdicts.is_empty() {
            s.push_str("<h2 id=\"verdicts\">Beyond the paper: its proposals measured, a verdict on each</h2>\n<ul>\n");
            for v in &self.verdicts {
                let _ = writeln!(s, "<li>{}</li>", e(v));
            }
            s.push_str("</ul>\n");
        }
        s.push_str("</body></html>\n");
        s
    }
}

fn html_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(label: &str, scene: &str, paper: f64, ours: Option<f64>, config: &str) -> Row {
        Row {
            label: label.into(),
            scene: scene.into(),
            paper_scene: String::new(),
            paper: Some(paper),
            ours,
            ratio: None,
            config: config.into(),
            missing: ours.is_none().then(|| "needs --sht, not built yet".into()),
        }
    }

    #[test]
    fn results_put_each_scene_beside_the_paper_with_nothing_of_the_host() {
        let report = Report {
            size: 64,
            scenes: vec![
                ReportScene {
                    id: "room".into(),
                    source: "/some/host/path".into(),
                    paper: "ERW6".into(),
                },
                ReportScene {
                    id: "beetle".into(),
                    source: "beetle".into(),
                    paper: "VW Beetle".into(),
                },
            ],
            tables: vec![Table {
                id: "table3".into(),
                title: "Table 3: SHT".into(),
                unit: "MRays/s".into(),
                note: "One SPE.".into(),
                rows: vec![
                    row("without", "room", 30.08, Some(37.924), "64x64, SHT off"),
                    row("without", "beetle", 5.3, Some(7.5), "64x64, SHT off"),
                    row("with", "room", 30.1, None, ""),
                    row("with", "beetle", 7.0, Some(123.456), "a|b"),
                ],
            }],
            figures: vec![Figure {
                id: "table3".into(),
                title: "plot".into(),
                files: vec!["figure2.svg".into()],
            }],
            jobs: 4,
            jobs_measured: 3,
            missing: vec!["x.json: absent".into()],
            heatmaps: vec![HeatMaps {
                scene: "room".into(),
                config: "c".into(),
                cycles: "jobs/room-heat.png".into(),
                wait: "jobs/room-heat-wait.png".into(),
            }],
            notes: vec!["a note".into()],
            verdicts: Vec::new(),
        };
        let md = report.to_results_markdown();
        let body = md
            .split_once("\n\nFrames of")
            .map(|(_, b)| format!("Frames of{b}"))
            .unwrap();
        assert_eq!(
            body,
            "Frames of 64x64 pixels; scenes: room (for the paper's ERW6), beetle (for the paper's VW Beetle); 3 of 4 runs measured. Every number of ours is the simulator's (cycles and counters, the same for any host and any `--threads`).

- a note
- missing: x.json: absent

## Table 3: SHT

One SPE.
Unit: MRays/s.

| row | ERW6 (paper) | room | VW Beetle (paper) | beetle | runs (ours) |
|---|---:|---:|---:|---:|---|
| without | 30.08 | 37.92 | 5.300 | 7.500 | 64x64, SHT off |
| with | 30.10 | – | 7.000 | 123.5 | a\\|b |

Not measured:
- with, room: needs --sht, not built yet
"
        );
        assert!(md.starts_with("# Ray Tracing on the Cell Processor"));
        for host in ["/some/host/path", "jobs/room-heat", "figure2.svg"] {
            assert!(!md.contains(host), "{host} in results.md");
        }
    }
}
