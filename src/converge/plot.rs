//! The time-against-error picture: an SVG with log-log axes, one curve per method, labelled axes and a
//! legend, written by hand (a few dozen elements; no plotting crate needed).

use std::fmt::Write as _;

/// One curve: a name and its points `(seconds, error)`, both positive, and how it is drawn.
pub struct Curve {
    /// The legend's label.
    pub name: String,
    /// Points in the order to join them.
    pub points: Vec<(f64, f64)>,
    /// Its colour, an index into a fixed palette (taken modulo its size).
    pub colour: usize,
    /// Its line's dash pattern, an index into a fixed set whose first is solid (modulo its size).
    pub dash: usize,
}

/// Plot width, in SVG user units, when the legend's labels fit in [`RIGHT`].
const W: f64 = 720.0;
/// Plot height.
const H: f64 = 480.0;
/// Margin left of the axes (tick labels and the y label).
const LEFT: f64 = 80.0;
/// Margin right of the axes (the legend), widened for longer labels.
const RIGHT: f64 = 180.0;
/// A generous width of one character of a 12-unit sans-serif label, for sizing the legend.
const CHAR_W: f64 = 7.0;
/// Margin above the axes (the title).
const TOP: f64 = 30.0;
/// Margin below the axes (tick labels and the x label).
const BOTTOM: f64 = 60.0;

/// Line colours, one per curve in turn (a colour-blind-safe set).
const COLOURS: [&str; 8] =
    ["#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#000000", "#F0E442"];

/// Dash patterns (`stroke-dasharray`), one per [`Curve::dash`]; the first is a solid line.
const DASHES: [&str; 5] = ["", "8 4", "2 3", "8 3 2 3", "14 4"];

/// The decades `10^a ..= 10^b` that cover `[lo, hi]`.
fn decades(lo: f64, hi: f64) -> (i32, i32) {
    (lo.log10().floor() as i32, hi.log10().ceil().max(lo.log10().floor() + 1.0) as i32)
}

/// The SVG text of the plot: x = seconds, y = `y_label` (both log scale), title on top.
pub fn svg(title: &str, y_label: &str, curves: &[Curve]) -> String {
    let points = curves.iter().flat_map(|c| c.points.iter().copied()).filter(|&(x, y)| x > 0.0 && y > 0.0);
    let (mut x_lo, mut x_hi, mut y_lo, mut y_hi) = (f64::MAX, f64::MIN_POSITIVE, f64::MAX, f64::MIN_POSITIVE);
    for (x, y) in points {
        (x_lo, x_hi, y_lo, y_hi) = (x_lo.min(x), x_hi.max(x), y_lo.min(y), y_hi.max(y));
    }
    if x_lo > x_hi {
        (x_lo, x_hi, y_lo, y_hi) = (1.0, 10.0, 1.0, 10.0);
    }
    let ((xa, xb), (ya, yb)) = (decades(x_lo, x_hi), decades(y_lo, y_hi));
    let (pw, ph) = (W - LEFT - RIGHT, H - TOP - BOTTOM);
    // The legend: a 24-unit line sample, then the label, inside the image whatever the labels' length.
    let longest = curves.iter().map(|c| c.name.chars().count()).max().unwrap_or(0) as f64;
    let right = RIGHT.max(16.0 + 30.0 + CHAR_W * longest + 8.0);
    let w = LEFT + pw + right;
    let sx = |x: f64| LEFT + (x.log10() - f64::from(xa)) / f64::from(xb - xa) * pw;
    let sy = |y: f64| TOP + ph - (y.log10() - f64::from(ya)) / f64::from(yb - ya) * ph;
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{H}" font-family="sans-serif" font-size="12">"#
    );
    let _ = writeln!(s, r#"<rect width="{w}" height="{H}" fill="white"/>"#);
    let _ = writeln!(
        s,
        r#"<text x="{}" y="18" text-anchor="middle" font-size="14">{}</text>"#,
        LEFT + pw / 2.0,
        escape(title)
    );
    for e in xa..=xb {
        let x = sx(10f64.powi(e));
        let _ =
            writeln!(s, r##"<line x1="{x:.1}" y1="{TOP}" x2="{x:.1}" y2="{:.1}" stroke="#ddd"/>"##, TOP + ph);
        let _ =
            writeln!(s, r#"<text x="{x:.1}" y="{:.1}" text-anchor="middle">1e{e}</text>"#, TOP + ph + 16.0);
    }
    for e in ya..=yb {
        let y = sy(10f64.powi(e));
        let _ = writeln!(
            s,
            r##"<line x1="{LEFT}" y1="{y:.1}" x2="{:.1}" y2="{y:.1}" stroke="#ddd"/>"##,
            LEFT + pw
        );
        let _ =
            writeln!(s, r#"<text x="{:.1}" y="{:.1}" text-anchor="end">1e{e}</text>"#, LEFT - 6.0, y + 4.0);
    }
    let _ =
        writeln!(s, r#"<rect x="{LEFT}" y="{TOP}" width="{pw}" height="{ph}" fill="none" stroke="black"/>"#);
    let _ = writeln!(
        s,
        r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">wall time (s)</text>"#,
        LEFT + pw / 2.0,
        H - 16.0
    );
    let _ = writeln!(
        s,
        r#"<text x="18" y="{:.1}" text-anchor="middle" transform="rotate(-90 18 {:.1})">{}</text>"#,
        TOP + ph / 2.0,
        TOP + ph / 2.0,
        escape(y_label)
    );
    // Legend rows 20 apart, closer when there are more than the plot's height holds.
    let row = (ph / curves.len().max(1) as f64).min(20.0);
    for (k, c) in curves.iter().enumerate() {
        let colour = COLOURS[c.colour % COLOURS.len()];
        let dash = match DASHES[c.dash % DASHES.len()] {
            "" => String::new(),
            d => format!(r#" stroke-dasharray="{d}""#),
        };
        let pts: Vec<String> = c
            .points
            .iter()
            .filter(|&&(x, y)| x > 0.0 && y > 0.0)
            .map(|&(x, y)| format!("{:.1},{:.1}", sx(x), sy(y)))
            .collect();
        let _ = writeln!(
            s,
            r#"<polyline points="{}" fill="none" stroke="{colour}" stroke-width="2"{dash}/>"#,
            pts.join(" ")
        );
        for p in &pts {
            let (x, y) = p.split_once(',').unwrap_or(("0", "0"));
            let _ = writeln!(s, r#"<circle cx="{x}" cy="{y}" r="3" fill="{colour}"/>"#);
        }
        let ly = TOP + 10.0 + row * k as f64;
        let lx = LEFT + pw + 16.0;
        let _ = writeln!(
            s,
            r#"<line x1="{lx}" y1="{ly}" x2="{}" y2="{ly}" stroke="{colour}" stroke-width="2"{dash}/>"#,
            lx + 24.0
        );
        let _ = writeln!(s, r#"<text x="{}" y="{:.1}">{}</text>"#, lx + 30.0, ly + 4.0, escape(&c.name));
    }
    s.push_str("</svg>\n");
    s
}

/// `text` with XML's special characters escaped.
fn escape(text: &str) -> String {
    text.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_plot_has_a_curve_and_a_legend_entry_per_method_and_labelled_axes() {
        let curves = [
            Curve {
                name: "grid".into(),
                points: vec![(0.01, 0.1), (0.04, 0.05), (0.16, 0.02)],
                colour: 0,
                dash: 0,
            },
            Curve {
                name: "r2 <low-discrepancy>".into(),
                points: vec![(0.01, 0.08), (0.04, 0.02)],
                colour: 1,
                dash: 1,
            },
        ];
        let s = svg("whitted.toml", "RMSE", &curves);
        assert_eq!(s.matches("<polyline").count(), 2);
        assert_eq!(s.matches("<circle").count(), 5);
        assert!(s.contains(">grid<") && s.contains("r2 &lt;low-discrepancy&gt;"));
        // The second curve is dashed, on the plot and in the legend; the first is solid.
        assert_eq!(s.matches(r#"stroke-dasharray="8 4""#).count(), 2);
        assert_eq!(s.matches("stroke-dasharray").count(), 2);
        assert!(s.contains("wall time (s)") && s.contains(">RMSE<"));
        // Decade ticks 1e-2 .. 1e0 on x (0.01 to 0.16), 1e-2 .. 1e-1 on y.
        assert!(s.contains(">1e-2<") && s.contains(">1e0<") && s.contains(">1e-1<"));
        assert!(s.starts_with("<svg") && s.trim_end().ends_with("</svg>"));
        // Short labels keep the default width; a longer one widens the image by what it needs (the label
        // starts 46 right of the axes, 7 a character, 8 to spare: 80 + 460 + 46 + 24·7 + 8).
        let curve = |name: &str| Curve { name: name.into(), points: vec![(0.1, 0.1)], colour: 0, dash: 2 };
        assert!(svg("t", "RMSE", &[curve("stratified")]).contains(r#"width="720""#));
        let s = svg("t", "RMSE", &[curve("grid"), curve("stratified, gaussian:1.5")]);
        assert!(s.contains(r#"width="762""#) && s.contains(r#"<text x="586""#), "{s}");
    }
}
