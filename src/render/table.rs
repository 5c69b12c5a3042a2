//! A small table of text cells, rendered as Markdown, HTML or plain text.

/// A titled table.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Table {
    pub title: String,
    pub header: Vec<String>,
    pub rows: Vec<Vec<String>>,
}

impl Table {
    pub fn new(title: &str, header: &[&str]) -> Table {
        Table {
            title: title.to_string(),
            header: header.iter().map(|s| s.to_string()).collect(),
            rows: Vec::new(),
        }
    }

    pub fn row(&mut self, cells: Vec<String>) {
        self.rows.push(cells);
    }

    /// A GitHub-flavoured Markdown table under a bold title.
    pub fn markdown(&self) -> String {
        let escape = |s: &str| s.replace('|', "\\|");
        let mut text = format!("**{}**\n\n", self.title);
        text += &format!(
            "| {} |\n",
            self.header
                .iter()
                .map(|h| escape(h))
                .collect::<Vec<_>>()
                .join(" | ")
        );
        text += &format!("|{}\n", "---|".repeat(self.header.len()));
        for row in &self.rows {
            text += &format!(
                "| {} |\n",
                row.iter()
                    .map(|c| escape(c))
                    .collect::<Vec<_>>()
                    .join(" | ")
            );
        }
        text
    }

    /// An HTML table with a caption.
    pub fn html(&self) -> String {
        let mut text = format!(
            "<table>\n<caption>{}</caption>\n<tr>",
            escape_html(&self.title)
        );
        for h in &self.header {
            text += &format!("<th>{}</th>", escape_html(h));
        }
        text += "</tr>\n";
        for row in &self.rows {
            text += "<tr>";
            for c in row {
                text += &format!("<td>{}</td>", escape_html(c));
            }
            text += "</tr>\n";
        }
        text + "</table>\n"
    }

    /// Aligned plain text for the terminal.
    pub fn text(&self) -> String {
        let columns = self.header.len();
        let mut widths: Vec<usize> = self.header.iter().map(|h| h.chars().count()).collect();
        for row in &self.rows {
            for (w, c) in widths.iter_mut().zip(row) {
                *w = (*w).max(c.chars().count());
            }
        }
        let line = |cells: &[String]| {
            let mut s = String::from(" ");
            for (k, c) in cells.iter().enumerate().take(columns) {
                let pad = widths[k].saturating_sub(c.chars().count());
                s += &format!(" {c}{} ", " ".repeat(pad));
            }
            s.trim_end().to_string() + "\n"
        };
        let mut text = format!("{}\n", self.title);
        text += &line(&self.header);
        text += &format!(
            "  {}\n",
            "-".repeat(widths.iter().map(|w| w + 2).sum::<usize>())
        );
        for row in &self.rows {
            text += &line(row);
        }
        text
    }
}

/// Escapes `&`, `<`, `>` and `"`.
pub fn escape_html(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}
