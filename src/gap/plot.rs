//! Figures as SVG files, written by hand: two panels per joint (recording vs simulation before and
//! after the fit; residuals with the ±2σ noise band). SVG needs no font or image library, opens in
//! any browser, and keeps the core free of plotting dependencies.

use std::fmt::Write as _;

use super::report::JointSeries;

const WIDTH: f64 = 900.0;
const PANEL: f64 = 260.0;
const MARGIN: f64 = 60.0;

struct Axes {
    t0: f64,
    t1: f64,
    y0: f64,
    y1: f64,
    top: f64,
}

impl Axes {
    fn x(&self, t: f64) -> f64 {
        MARGIN + (t - self.t0) / (self.t1 - self.t0).max(1e-12) * (WIDTH - 2.0 * MARGIN)
    }
    fn y(&self, v: f64) -> f64 {
        self.top + PANEL - (v - self.y0) / (self.y1 - self.y0).max(1e-12) * PANEL
    }
}

fn range(series: &[&[f64]]) -> (f64, f64) {
    let (lo, hi) = series
        .iter()
        .flat_map(|s| s.iter())
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
    if lo.is_finite() {
        let pad = 0.05 * (hi - lo).max(1e-9);
        (lo - pad, hi + pad)
    } else {
        (-1.0, 1.0)
    }
}

fn polyline(out: &mut String, ax: &Axes, t: &[f64], v: &[f64], colour: &str, width: f64) {
    let mut open = false;
    for (ti, vi) in t.iter().zip(v) {
        if vi.is_finite() {
            if !open {
                let _ = write!(out, r#"<polyline fill="none" stroke="{colour}" stroke-width="{width}" points=""#);
                open = true;
            }
            let _ = write!(out, "{:.1},{:.1} ", ax.x(*ti), ax.y(*vi));
        } else if open {
            out.push_str("\"/>\n");
            open = false;
        }
    }
    if open {
        out.push_str("\"/>\n");
    }
}

fn frame(out: &mut String, ax: &Axes, title: &str, unit: &str) {
    let _ = writeln!(
        out,
        r##"<rect x="{MARGIN}" y="{}" width="{}" height="{PANEL}" fill="none" stroke="#888"/><text x="{MARGIN}" y="{}" font-size="14">{title}</text>"##,
        ax.top,
        WIDTH - 2.0 * MARGIN,
        ax.top - 6.0
    );
    for k in 0..=4 {
        let v = ax.y0 + (ax.y1 - ax.y0) * f64::from(k) / 4.0;
        let t = ax.t0 + (ax.t1 - ax.t0) * f64::from(k) / 4.0;
        let _ = writeln!(out, r#"<text x="4" y="{:.1}" font-size="11">{v:.3}</text>"#, ax.y(v) + 4.0);
        let _ = writeln!(out, r#"<text x="{:.1}" y="{:.1}" font-size="11">{t:.1} s</text>"#, ax.x(t) - 10.0, ax.top + PANEL + 14.0);
    }
    let _ = writeln!(out, r#"<text x="4" y="{:.1}" font-size="11">{unit}</text>"#, ax.top + 10.0);
}

/// One joint's figure: recording, simulation as modelled and as fitted; residuals before and after.
#[must_use]
pub fn joint_svg(s: &JointSeries) -> String {
    let height = 2.0 * PANEL + 3.0 * MARGIN;
    let mut out = format!(
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{WIDTH}" height="{height}" font-family="sans-serif"><rect width="100%" height="100%" fill="white"/>"#
    );
    out.push('\n');
    let (t0, t1) = (s.time_s.first().copied().unwrap_or(0.0), s.time_s.last().copied().unwrap_or(1.0));
    let (y0, y1) = range(&[&s.measured, &s.simulated_before, &s.simulated_after]);
    let top = Axes { t0, t1, y0, y1, top: MARGIN };
    frame(&mut out, &top, &format!("{}: recording (black), model (red), fitted (blue)", s.joint), s.unit);
    polyline(&mut out, &top, &s.time_s, &s.simulated_before, "#d62728", 1.5);
    polyline(&mut out, &top, &s.time_s, &s.simulated_after, "#1f77b4", 1.5);
    for (t, v) in s.time_s.iter().zip(&s.measured) {
        if v.is_finite() {
            let _ = write!(out, r#"<circle cx="{:.1}" cy="{:.1}" r="1.2"/>"#, top.x(*t), top.y(*v));
        }
    }
    out.push('\n');
    let (r0, r1) = range(&[&s.residual_before, &s.residual_after]);
    let bottom = Axes { t0, t1, y0: r0.min(-3.0 * s.noise_sigma), y1: r1.max(3.0 * s.noise_sigma), top: 2.0 * MARGIN + PANEL };
    frame(&mut out, &bottom, "residual: model (red), fitted (blue), ±2σ noise (grey)", s.unit);
    let band_top = bottom.y(2.0 * s.noise_sigma);
    let _ = writeln!(
        out,
        r##"<rect x="{MARGIN}" y="{band_top:.1}" width="{}" height="{:.1}" fill="#ccc" opacity="0.5"/>"##,
        WIDTH - 2.0 * MARGIN,
        (bottom.y(-2.0 * s.noise_sigma) - band_top).max(0.5)
    );
    polyline(&mut out, &bottom, &s.time_s, &s.residual_before, "#d62728", 1.0);
    polyline(&mut out, &bottom, &s.time_s, &s.residual_after, "#1f77b4", 1.0);
    out.push_str("</svg>\n");
    out
}
