//! Helpers shared by the integration tests that read the figures the CLI writes.

/// The `<text>` contents of an SVG document (trimmed).
pub fn svg_texts(svg: &str) -> Vec<String> {
    svg.split("<text")
        .skip(1)
        .filter_map(|t| Some(t[t.find('>')? + 1..t.find("</text>")?].trim().to_string()))
        .collect()
}

/// The figure has real axes: at least `n` numeric tick labels, and every `label`.
pub fn assert_figure(svg: &str, n: usize, labels: &[&str]) {
    let texts = svg_texts(svg);
    assert!(texts.iter().filter(|t| t.parse::<f64>().is_ok()).count() >= n, "too few tick labels: {texts:?}");
    for l in labels {
        assert!(texts.iter().any(|t| t == l), "`{l}` missing: {texts:?}");
    }
}
