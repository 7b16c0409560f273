//! A tiny HTML builder for the report (self-contained: inline CSS and SVG).

/// Escapes text for HTML.
pub fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

const STYLE: &str = "body{font-family:system-ui,-apple-system,'Segoe UI',sans-serif;max-width:1320px;\
margin:2em auto;padding:0 1em;color:#222;line-height:1.45}\
h1{font-size:1.6em}h3{margin-top:1.5em}h2{margin-top:2em;border-bottom:1px solid #ddd;padding-bottom:.2em}\
table{border-collapse:collapse;margin:1em 0;font-size:.92em}\
th,td{border:1px solid #ccc;padding:.3em .6em;text-align:right;vertical-align:top}\
th{background:#f3f3f3}td:first-child,th:first-child{text-align:left}\
.views{display:flex;flex-wrap:wrap;gap:1em}.views svg{border:1px solid #eee}\
.ok{color:#1a7f37}.bad{color:#c62828}code{background:#f5f5f5;padding:0 .2em}\
nav{margin:1em 0}nav a{color:#0b5cad}\
blockquote.published{border-left:4px solid #0b5cad;background:#f4f8fc;margin:1em 0;padding:.5em 1em}\
#pkm-view3d{border:1px solid #ddd;min-height:520px}#pkm-view3d canvas{display:block;max-width:100%}\
.view3d-bar{padding:.4em;font-size:.9em;background:#fafafa;border-top:1px solid #eee}\
.view3d-readout{padding:.2em .4em;font:12px monospace;white-space:pre-wrap}";

/// Collects the page's script errors and console errors in `window.pkmErrors` (run
/// first, so an error of any later script is seen; the browser test reads it).
const ERRORS: &str = "<script>window.pkmErrors=[];addEventListener('error',function(e){pkmErrors.push(String(e.message))});\
(function(){var c=console.error;console.error=function(){pkmErrors.push(Array.prototype.join.call(arguments,' '));c.apply(console,arguments)}})();</script>";

/// Accumulates the body of a page.
pub struct Html {
    title: String,
    body: String,
}

impl Html {
    pub fn new(title: &str) -> Self {
        Html {
            title: title.into(),
            body: String::new(),
        }
    }

    pub fn h1(&mut self, t: &str) {
        self.body.push_str(&format!("<h1>{}</h1>\n", esc(t)));
    }

    pub fn h2_id(&mut self, id: &str, t: &str) {
        self.body
            .push_str(&format!("<h2 id=\"{id}\">{}</h2>\n", esc(t)));
    }

    /// A paragraph of trusted HTML.
    pub fn p(&mut self, html: &str) {
        self.body.push_str(&format!("<p>{html}</p>\n"));
    }

    pub fn raw(&mut self, html: &str) {
        self.body.push_str(html);
        self.body.push('\n');
    }

    pub fn details(&mut self, summary: &str, html: &str) {
        self.body.push_str(&format!(
            "<details><summary>{}</summary>{html}</details>\n",
            esc(summary)
        ));
    }

    /// A table of trusted HTML cells.
    pub fn table(&mut self, head: &[&str], rows: &[Vec<String>]) {
        self.body.push_str(&Self::table_string(head, rows));
    }

    pub fn table_string(head: &[&str], rows: &[Vec<String>]) -> String {
        let mut s = String::from("<table><thead><tr>");
        for h in head {
            s.push_str(&format!("<th>{}</th>", esc(h)));
        }
        s.push_str("</tr></thead><tbody>");
        for r in rows {
            s.push_str("<tr>");
            for c in r {
                s.push_str(&format!("<td>{c}</td>"));
            }
            s.push_str("</tr>");
        }
        s.push_str("</tbody></table>\n");
        s
    }

    /// The body written so far (a section rendered on its own).
    pub fn body(self) -> String {
        self.body
    }

    pub fn finish(self) -> String {
        format!(
            "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
             <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\
             <title>{}</title><style>{STYLE}</style>{ERRORS}</head><body>\n{}</body></html>\n",
            esc(&self.title),
            self.body
        )
    }
}
