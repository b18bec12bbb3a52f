//! Self-contained HTML reports: one file a person can open anywhere, with every plot inlined as
//! SVG and no network access (no scripts, fonts or style sheets fetched).

use std::fmt::Write;

/// An HTML report being assembled, section by section.
#[derive(Debug, Clone)]
pub struct HtmlReport {
    title: String,
    body: String,
    figures: Vec<String>,
}

impl HtmlReport {
    pub fn new(title: impl Into<String>) -> Self {
        HtmlReport { title: title.into(), body: String::new(), figures: Vec::new() }
    }

    pub fn heading(&mut self, text: &str) -> &mut Self {
        let _ = writeln!(self.body, "<h2>{}</h2>", escape(text));
        self
    }

    /// A paragraph holding one link to a file beside the report.
    pub fn link(&mut self, href: &str, text: &str) -> &mut Self {
        let _ = writeln!(self.body, "<p><a href=\"{}\">{}</a></p>", escape(href), escape(text));
        self
    }

    /// Says what made the report: the command line as run (it names the scenario file) and its
    /// seed. The coopnav version is on every report (see [`HtmlReport::render`]).
    pub fn provenance(&mut self, command: &str, seed: Option<u64>) -> &mut Self {
        let seed = seed.map_or(String::new(), |s| format!(" · seed {s}"));
        let _ = writeln!(self.body, "<p class=\"provenance\">Run: <code>{}</code>{seed}</p>", escape(command));
        self
    }

    pub fn paragraph(&mut self, text: &str) -> &mut Self {
        let _ = writeln!(self.body, "<p>{}</p>", escape(text));
        self
    }

    /// A table with a header row; every cell is escaped.
    pub fn table<R: AsRef<[String]>>(&mut self, header: &[&str], rows: &[R]) -> &mut Self {
        self.body.push_str("<table>\n<tr>");
        for h in header {
            let _ = write!(self.body, "<th>{}</th>", escape(h));
        }
        self.body.push_str("</tr>\n");
        for row in rows {
            self.body.push_str("<tr>");
            for cell in row.as_ref() {
                let _ = write!(self.body, "<td>{}</td>", escape(cell));
            }
            self.body.push_str("</tr>\n");
        }
        self.body.push_str("</table>\n");
        self
    }

    /// An inline SVG figure; `id` names it (the same name as the SVG file written beside the
    /// report, so a reader can find either).
    pub fn figure(&mut self, id: &str, caption: &str, svg: &str) -> &mut Self {
        let _ = writeln!(
            self.body,
            "<figure id=\"{}\">\n{}\n<figcaption>{}</figcaption>\n</figure>",
            escape(id),
            strip_xml_prolog(svg),
            escape(caption)
        );
        self.figures.push(id.to_string());
        self
    }

    /// Ids of the figures added so far, in order.
    pub fn figures(&self) -> &[String] {
        &self.figures
    }

    pub fn render(&self) -> String {
        format!(
            "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>{title}</title>\n<style>{STYLE}</style>\n</head>\n<body>\n<h1>{title}</h1>\n{body}<footer>coopnav {version}</footer>\n</body>\n</html>\n",
            title = escape(&self.title),
            version = env!("CARGO_PKG_VERSION"),
            body = self.body
        )
    }
}

const STYLE: &str = "body{font-family:sans-serif;max-width:960px;margin:2em auto;color:#222}\
table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #bbb;padding:4px 8px;text-align:right}\
th{background:#eee}figure{margin:1.5em 0}figcaption{font-style:italic;color:#555}svg{max-width:100%;height:auto}";

fn strip_xml_prolog(svg: &str) -> &str {
    match svg.find("<svg") {
        Some(i) => &svg[i..],
        None => svg,
    }
}

/// Escapes text for HTML element content and attribute values.
pub fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::plot::{line_svg, Labels, Series};

    #[test]
    fn report_inlines_figures_and_escapes_text() {
        let svg = line_svg(Labels { title: "err", x: "t", y: "m" }, &[Series::new("a", vec![(0.0, 1.0), (1.0, 2.0)])])
            .unwrap();
        let mut r = HtmlReport::new("Run <1>");
        r.heading("Summary").paragraph("a & b").table(&["k", "v"], &[vec!["x<y".to_string(), "2".to_string()]]);
        r.figure("error.svg", "Error vs time", &svg);
        let html = r.render();
        assert!(html.contains("<title>Run &lt;1&gt;</title>"));
        assert!(html.contains("a &amp; b") && html.contains("<td>x&lt;y</td>"));
        assert!(html.contains("<figure id=\"error.svg\">\n<svg"));
        for fetches in ["<script", "<link", "src=\"http", "href=\"http", "@import"] {
            assert!(!html.contains(fetches), "report must be self-contained, found {fetches}");
        }
        assert_eq!(r.figures(), &["error.svg".to_string()]);
    }

    #[test]
    fn every_report_names_its_version_and_the_command_that_made_it() {
        let mut r = HtmlReport::new("Run");
        assert!(r.render().contains(&format!("coopnav {}", env!("CARGO_PKG_VERSION"))));
        r.provenance("coopnav simulate scenarios/full-stack.toml -o <x>", Some(7));
        let html = r.render();
        assert!(
            html.contains("<code>coopnav simulate scenarios/full-stack.toml -o &lt;x&gt;</code> · seed 7"),
            "{html}"
        );
    }
}
