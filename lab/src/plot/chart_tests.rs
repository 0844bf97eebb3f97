//! Tests of [`super::Chart`]: legend placement, SVG content, bad points, sizes, equal aspect.

use super::*;
use crate::plot::tests::{assert_contains, decay, energy_chart};

fn ellipse() -> Vec<(f64, f64)> {
    let th = (0..=200).map(|i| f64::from(i) * std::f64::consts::TAU / 200.0);
    th.map(|t| (2.0 * t.cos() - 1.0, t.sin())).collect()
}

/// The x coordinate of the `<text>` element that shows `label`.
fn text_x(svg: &str, label: &str) -> f64 {
    let end = svg.find(&format!(">\n{label}\n</text>")).unwrap();
    let start = svg[..end].rfind("<text").unwrap();
    let tag = &svg[start..end];
    let x = tag.find(" x=\"").unwrap() + 4;
    tag[x..x + tag[x..].find('"').unwrap()].parse().unwrap()
}

/// The legend goes to the corner with the least data: upper right when that is free (the
/// default), elsewhere when a curve runs through it. Negative control: the same chart
/// with the curve in the lower left keeps it upper right.
#[test]
fn legend_avoids_the_data() {
    let chart = |pts: Vec<(f64, f64)>| {
        Chart::new("legend", "x", "y")
            .with_series(Series::line("a rather long series label", pts))
            .with_series(Series::markers(
                "anchor",
                [(0.0, 0.0), (1.0, 0.0), (0.5, 1.0)],
            ))
            .to_svg_string()
            .unwrap()
    };
    let through_upper_right: Vec<(f64, f64)> = (0..=50)
        .map(|i| (0.6 + f64::from(i) / 125.0, 1.0))
        .collect();
    let svg = chart(through_upper_right);
    assert!(text_x(&svg, "anchor") < 400.0, "{}", text_x(&svg, "anchor"));
    let lower_left: Vec<(f64, f64)> = (0..=50).map(|i| (f64::from(i) / 100.0, 0.0)).collect();
    let svg = chart(lower_left);
    assert!(text_x(&svg, "anchor") > 400.0, "{}", text_x(&svg, "anchor"));
}

/// Drawn data points (polyline vertices and circle centres, drawn before the legend)
/// inside the legend box (the rectangle with the legend's translucent background).
fn data_under_legend(svg: &str) -> usize {
    let attr = |tag: &str, name: &str| -> f64 {
        let at = tag.find(&format!(" {name}=\"")).unwrap() + name.len() + 3;
        tag[at..at + tag[at..].find('"').unwrap()].parse().unwrap()
    };
    let legend = svg.find("opacity=\"0.85\"").unwrap();
    let start = svg[..legend].rfind("<rect").unwrap();
    let rect = &svg[start..legend];
    let (x0, y0) = (attr(rect, "x"), attr(rect, "y"));
    let (x1, y1) = (x0 + attr(rect, "width"), y0 + attr(rect, "height"));
    // The data are drawn before the legend box, the legend's own samples after it.
    let data = &svg[..start];
    let mut points = Vec::new();
    for line in data.split("<polyline").skip(1) {
        let at = line.find("points=\"").unwrap() + 8;
        let text = &line[at..at + line[at..].find('"').unwrap()];
        for p in text.split_whitespace() {
            let (a, b) = p.split_once(',').unwrap();
            points.push((a.parse::<f64>().unwrap(), b.parse::<f64>().unwrap()));
        }
    }
    for c in data.split("<circle").skip(1) {
        points.push((attr(c, "cx"), attr(c, "cy")));
    }
    points
        .iter()
        .filter(|(px, py)| (x0..=x1).contains(px) && (y0..=y1).contains(py))
        .count()
}

/// The Kepler orbit of `gvi run kepler --plot` fills the equal-aspect plot and reaches
/// every corner, so any corner legend would hide part of it (the README figure);
/// `legend_clear_of_data`, which the run's chart sets, raises the y range until the
/// legend sits above the orbit, in the 800 px image. Negative control: without it every
/// corner would cover the orbit, and the legend moves to a panel right of the plot.
#[test]
fn legend_clear_of_data_leaves_the_orbit_visible() {
    let scene = crate::scene::Scene::load("kepler")
        .unwrap()
        .build()
        .unwrap();
    let options = crate::run::RunOptions {
        chart: true,
        ..Default::default()
    };
    let mut chart = crate::run::run_scene(&scene, options)
        .unwrap()
        .chart
        .unwrap();
    assert!(chart.keep_legend_clear);
    let clear = chart.to_svg_string().unwrap();
    assert_eq!(data_under_legend(&clear), 0);
    assert_eq!(svg_width(&clear), 800.0);
    chart.keep_legend_clear = false;
    let data = chart.prepared();
    let (size, x, y) = chart.layout(&data).unwrap();
    let coverage = chart.corner_coverage(&data, size, (x.lo, x.hi), (y.lo, y.hi));
    assert!(
        coverage.iter().all(|c| c.1 > 10),
        "negative control: every corner covers the orbit ({:?})",
        coverage.map(|c| c.1)
    );
    let outside = chart.to_svg_string().unwrap();
    assert_eq!(data_under_legend(&outside), 0);
    assert!(svg_width(&outside) > 800.0);
}

/// The coverage count the legend tests rely on finds points under a box.
#[test]
fn data_under_legend_counts_covered_points() {
    let svg = "<polyline points=\"10,10 50,50 150,150\"/><circle cx=\"20\" cy=\"90\"/>\
               <rect x=\"0\" y=\"0\" width=\"100\" height=\"100\" fill-opacity=\"0.85\"/>";
    assert_eq!(data_under_legend(svg), 3);
}

/// The image width written in the SVG's root element.
fn svg_width(svg: &str) -> f64 {
    let at = svg.find(" width=\"").unwrap() + 8;
    svg[at..at + svg[at..].find('"').unwrap()].parse().unwrap()
}

/// A work–precision chart holds data in every corner (the Kepler study's 27 series), so
/// any corner legend hid some of it: the legend goes into a panel right of the plot, which
/// widens the image and leaves the plot its size. Negative control: with the upper right
/// corner free, the same legend stays inside the 800 px image, in that corner.
#[test]
fn legend_moves_outside_when_every_corner_holds_data() {
    let grid = |skip_upper_right: bool| -> Vec<(f64, f64)> {
        let cells = (0..=20).flat_map(|i| (0..=20).map(move |j| (f64::from(i), f64::from(j))));
        cells
            .filter(|&(x, y)| !(skip_upper_right && x > 10.0 && y > 10.0))
            .collect()
    };
    let chart = |pts: Vec<(f64, f64)>| {
        let mut c = Chart::new("crowded", "x", "y");
        for k in 0..8 {
            let label = format!("series {k} with a longer label");
            let mine = pts.iter().copied().skip(k).step_by(8);
            c.push(Series::markers(label, mine));
        }
        c.to_svg_string().unwrap()
    };
    let outside = chart(grid(false));
    assert!(svg_width(&outside) > 1000.0, "{}", svg_width(&outside));
    assert_eq!(data_under_legend(&outside), 0);
    // The labels sit right of the 800 px plot image.
    assert!(text_x(&outside, "series 7 with a longer label") > 800.0);
    let inside = chart(grid(true));
    assert_eq!(svg_width(&inside), 800.0);
    assert_eq!(data_under_legend(&inside), 0);
    let x = text_x(&inside, "series 7 with a longer label");
    assert!((400.0..800.0).contains(&x), "{x}");
}

#[test]
fn svg_contains_title_labels_ticks_and_legend() {
    let svg = energy_chart().to_svg_string().unwrap();
    assert_contains(&svg, &["Energy &lt;error&gt;", "time t", "|H(t) - H(0)|"]);
    assert_contains(&svg, &["cG(2)", "Störmer-Verlet", "spectral", "order 4"]);
    assert_contains(
        &svg,
        &["1e-12", "1e-2", "1e0", ">\n0\n</text>", ">\n40\n</text>"],
    );
    assert!(
        svg.matches("<polyline").count() > 50,
        "dashes are separate polylines"
    );
}

#[test]
fn log_axes_drop_bad_points() {
    let bad = [
        (2.0, -1.0),
        (3.0, 0.0),
        (4.0, f64::NAN),
        (f64::INFINITY, 1.0),
    ];
    let pts = [&[(1.0, 1e-3)], &bad[..], &[(5.0, 0.1)]].concat();
    let chart = Chart::new("t", "x", "y")
        .log_y()
        .with_series(Series::markers("m", pts));
    // Two surviving points plus the legend marker.
    assert_eq!(chart.to_svg_string().unwrap().matches("<circle").count(), 3);
    let chart = chart.log_x();
    let runs = &chart.prepared()[0].2;
    assert_eq!(runs, &[vec![(0.0, -3.0)], vec![(5f64.log10(), -1.0)]]);
}

#[test]
fn no_data_errors() {
    let empty = Chart::new("nothing", "x", "y");
    let err = empty.to_svg_string();
    assert!(matches!(err, Err(PlotError::NoData { title }) if title == "nothing"));
    let bad = Series::line("b", [(1.0, -2.0), (f64::NAN, 1.0)]);
    let chart = empty
        .log_y()
        .with_series(Series::line("a", vec![]))
        .with_series(bad);
    assert!(matches!(
        chart.to_svg_string(),
        Err(PlotError::NoData { .. })
    ));
    // An empty series next to a good one is skipped, legend entry included.
    let mut chart = Chart::new("ok", "x", "y").with_series(Series::line("empty", vec![]));
    chart.push(Series::line("good", decay(1.0)));
    let svg = chart.to_svg_string().unwrap();
    assert!(svg.contains("good") && !svg.contains("empty"));
}

#[test]
fn extreme_inputs_do_not_panic() {
    let huge = Series::dashed("d", [(f64::MAX, 1.0), (-f64::MAX, -1.0)]);
    let huge = Chart::new("big", "x", "y")
        .with_series(huge)
        .to_svg_string();
    assert!(matches!(huge, Err(PlotError::InvalidData { .. })));
    let single = Chart::new("", "", "").with_series(Series::line_markers("", [(1.0, 1.0)]));
    assert!(single.clone().size(0, 0).to_svg_string().is_ok());
    assert!(
        single
            .log_x()
            .log_y()
            .equal_aspect()
            .to_svg_string()
            .is_ok()
    );
    let odd = [
        (5e-324, 1e-320),
        (1.0, 1.0 + 1e-15),
        (f64::MAX, f64::MIN_POSITIVE),
    ];
    let odd = Series::line_markers("p", odd).with_color(99);
    let chart = Chart::new("a", "x", "y").with_series(odd);
    assert!(chart.to_svg_string().is_ok());
    assert!(chart.log_x().log_y().equal_aspect().to_svg_string().is_ok());
    let flat = Series::line("f", [(0.0, 0.0), (0.0, 0.0)]);
    let flat = Chart::new("flat", "x", "y")
        .with_series(flat)
        .size(20_000, 1);
    assert!(flat.equal_aspect().to_svg_string().is_ok());
}

#[test]
fn equal_aspect_orbit() {
    for title in ["Kepler orbit", ""] {
        let chart = Chart::new(title, "q1", "q2").with_series(Series::line("orbit", ellipse()));
        let chart = chart.equal_aspect();
        let (size, x, y) = chart.layout(&chart.prepared()).unwrap();
        let (pw, ph) = plot_area_size(size, title);
        // The layout arithmetic must match plotters' actual plotting area.
        assert_eq!(chart.render(&mut String::new()).unwrap(), (pw, ph));
        let (ux, uy) = ((x.hi - x.lo) / f64::from(pw), (y.hi - y.lo) / f64::from(ph));
        assert!((ux - uy).abs() < 1e-12 * ux, "{ux} vs {uy}");
        assert!(x.lo < -3.0 && x.hi > 1.0 && y.lo < -1.0 && y.hi > 1.0);
    }
}
