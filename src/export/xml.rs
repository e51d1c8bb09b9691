//! A small XML writer (roxmltree only reads): elements, attributes escaped, two-space indent.

use std::fmt::Write as _;

/// Text of an XML document being written.
pub(crate) struct XmlWriter {
    out: String,
    open: Vec<&'static str>,
}

/// Escapes text for a double-quoted attribute value.
pub(crate) fn escape(value: &str) -> String {
    let mut s = String::with_capacity(value.len());
    for c in value.chars() {
        match c {
            '&' => s.push_str("&amp;"),
            '<' => s.push_str("&lt;"),
            '>' => s.push_str("&gt;"),
            '"' => s.push_str("&quot;"),
            '\'' => s.push_str("&apos;"),
            '\n' => s.push_str("&#10;"),
            '\t' => s.push_str("&#9;"),
            '\r' => s.push_str("&#13;"),
            c if (c as u32) < 0x20 => {}
            c => s.push(c),
        }
    }
    s
}

impl XmlWriter {
    pub fn new() -> Self {
        Self { out: String::from("<?xml version=\"1.0\" encoding=\"utf-8\"?>\n"), open: Vec::new() }
    }

    fn start(&mut self, tag: &str, attrs: &[(&str, String)]) {
        for _ in 0..self.open.len() {
            self.out.push_str("  ");
        }
        self.out.push('<');
        self.out.push_str(tag);
        for (k, v) in attrs {
            // Writing into a String cannot fail.
            let _ = write!(self.out, " {k}=\"{}\"", escape(v));
        }
    }

    /// `<tag attrs>`; close it with [`Self::close`].
    pub fn open(&mut self, tag: &'static str, attrs: &[(&str, String)]) {
        self.start(tag, attrs);
        self.out.push_str(">\n");
        self.open.push(tag);
    }

    /// `<tag attrs/>`.
    pub fn empty(&mut self, tag: &str, attrs: &[(&str, String)]) {
        self.start(tag, attrs);
        self.out.push_str("/>\n");
    }

    /// `<!-- text -->` (`--` in the text is broken up).
    pub fn comment(&mut self, text: &str) {
        for _ in 0..self.open.len() {
            self.out.push_str("  ");
        }
        let _ = writeln!(self.out, "<!-- {} -->", text.replace("--", "- -"));
    }

    /// Closes the innermost open element.
    pub fn close(&mut self) {
        if let Some(tag) = self.open.pop() {
            for _ in 0..self.open.len() {
                self.out.push_str("  ");
            }
            let _ = writeln!(self.out, "</{tag}>");
        }
    }

    /// The document, every open element closed.
    pub fn finish(mut self) -> String {
        while !self.open.is_empty() {
            self.close();
        }
        self.out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn attributes_are_escaped_and_parse_back() {
        let mut w = XmlWriter::new();
        w.open("a", &[("name", "x\"<&>'y\nz".to_owned())]);
        w.empty("b", &[("v", "1 2 3".to_owned())]);
        w.comment("a -- b");
        let text = w.finish();
        let doc = roxmltree::Document::parse(&text).expect("well-formed");
        assert_eq!(doc.root_element().attribute("name"), Some("x\"<&>'y\nz"));
        assert_eq!(doc.root_element().children().filter(roxmltree::Node::is_element).count(), 1);
    }
}
