//! How tables are printed (`TableFormat`), and the plain table of named rows the studies share.

/// How a study is printed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TableFormat {
    /// Aligned columns for a terminal.
    Text,
    /// GitHub-flavoured Markdown tables.
    Markdown,
}

/// A plain table: a left-aligned first column (names) and right-aligned others.
pub(super) fn plain_table(
    title: &str,
    header: &[&str],
    rows: &[Vec<String>],
    format: TableFormat,
) -> String {
    let mut s = String::new();
    match format {
        TableFormat::Markdown => {
            s += &format!("**{title}**\n\n| {} |\n", header.join(" | "));
            let align: Vec<&str> =
                (0..header.len()).map(|k| if k == 0 { "---" } else { "---:" }).collect();
            s += &format!("| {} |\n", align.join(" | "));
            for r in rows {
                s += &format!("| {} |\n", r.join(" | "));
            }
        }
        TableFormat::Text => {
            let width = |k: usize| {
                rows.iter()
                    .map(|r| r[k].chars().count())
                    .chain([header[k].len()])
                    .max()
                    .unwrap_or(0)
            };
            let widths: Vec<usize> = (0..header.len()).map(width).collect();
            let line = |cells: Vec<&str>| {
                let mut l = String::new();
                for (k, c) in cells.iter().enumerate() {
                    let pad = widths[k] - c.chars().count();
                    if k == 0 {
                        l += &format!("{c}{}", " ".repeat(pad));
                    } else {
                        l += &format!("  {}{c}", " ".repeat(pad));
                    }
                }
                l + "\n"
            };
            s += &format!("{title}\n\n");
            s += &line(header.to_vec());
            for r in rows {
                s += &line(r.iter().map(String::as_str).collect());
            }
        }
    }
    s
}
