//! The report's pages from their Tera templates (`templates/report/`, embedded in the binary):
//! the engine escapes every value it is given, with the one escaping function of the reports,
//! [`esc`]; a value marked `safe` in a template is one the page builds itself (the style sheet, a
//! figure's base64).

use base64::Engine as _;
use serde::Serialize;

use super::plots::Figure;

/// The page templates, by the names they include each other by (autoescaped: they end in
/// `.html`).
const TEMPLATES: &[(&str, &str)] = &[
    ("report.html", include_str!("../../templates/report/report.html.tera")),
    ("measured.html", include_str!("../../templates/report/measured.html.tera")),
    ("advice.html", include_str!("../../templates/report/advice.html.tera")),
    ("figure.html", include_str!("../../templates/report/figure.html.tera")),
    ("points.html", include_str!("../../templates/report/points.html.tera")),
    ("headers.html", include_str!("../../templates/report/headers.html.tera")),
    ("calibration.html", include_str!("../../templates/report/calibration.html.tera")),
];

/// Text made safe inside an HTML element or a double-quoted attribute.
pub fn esc(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

/// The page `name` rendered from `context`.
pub fn render(name: &str, context: &impl Serialize) -> String {
    let mut tera = tera::Tera::default();
    tera.autoescape_on(vec![".html"]);
    tera.set_escape_fn(esc);
    tera.add_raw_templates(TEMPLATES.iter().copied()).expect("the report's templates parse");
    let context = tera::Context::from_serialize(context).expect("the report's context is a map");
    // The templates and their contexts are ours: a failure here is a bug, not bad input.
    tera.render(name, &context).unwrap_or_else(|e| panic!("the report template {name}: {}", chain(&e)))
}

fn chain(e: &dyn std::error::Error) -> String {
    let mut s = e.to_string();
    let mut source = e.source();
    while let Some(c) = source {
        s.push_str(": ");
        s.push_str(&c.to_string());
        source = c.source();
    }
    s
}

/// A figure as a template shows it: its caption, file name and PNG as base64.
#[derive(Serialize)]
pub struct FigureView<R: Serialize> {
    pub name: String,
    pub caption: String,
    pub png: String,
    /// Whether the figure labels points by `#index`, and their rows.
    pub labelled: bool,
    pub rows: Vec<R>,
}

impl FigureView<()> {
    pub fn of(f: &Figure) -> FigureView<()> {
        FigureView::with_rows(f, Vec::new())
    }
}

impl<R: Serialize> FigureView<R> {
    pub fn with_rows(f: &Figure, rows: Vec<R>) -> FigureView<R> {
        FigureView {
            name: f.name.clone(),
            caption: f.caption.clone(),
            png: base64::engine::general_purpose::STANDARD.encode(&f.png),
            labelled: !f.points.is_empty(),
            rows,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_engine_escapes_values_with_esc_and_leaves_safe_ones() {
        #[derive(Serialize)]
        struct Headers {
            headers: Vec<serde_json::Value>,
        }
        let page = render(
            "headers.html",
            &Headers { headers: vec![serde_json::json!({"name": "a<b & \"c\" 'd'/", "unit": "m/s"})] },
        );
        assert_eq!(page, "<th>a&lt;b &amp; &quot;c&quot; 'd'/ (m/s)</th>");
    }
}
