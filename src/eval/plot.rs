//! Table I as a picture: per-object success of every evaluated agent side by side, as
//! horizontal bars with their Wilson 95 % intervals, one group of bars per object and a
//! first group for each agent's mean (SVG drawn with plotters, in the style of
//! [`crate::train::plot`]).
//!
//! Objects are sorted by the first agent's margin over the best other agent (largest
//! first), so the objects where the first agent (usually the policy under study) wins and
//! loses stand at the two ends. The height grows with the number of objects and agents,
//! so 19 and 61 objects are equally legible.

use super::{AgentResult, EvalError};
use crate::train::plot::PALETTE;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::Path;

/// Width of the image (px).
const WIDTH: u32 = 1000;
/// Font size of the object names and the legend (plotters' size; about 13 px in the SVG).
const LABEL_FONT: u32 = 16;

/// The order in which objects are drawn (indices into the first agent's objects): by
/// the first agent's success rate minus the best other agent's, largest margin first;
/// ties by the first agent's rate (higher first), then by the set's order. With a single
/// agent, by its rate.
pub fn object_order(results: &[AgentResult]) -> Vec<usize> {
    let Some(first) = results.first() else {
        return Vec::new();
    };
    let margin = |i: usize| -> f64 {
        let own = first.objects[i].rate;
        let best_other = results[1..]
            .iter()
            .filter_map(|r| r.objects.get(i).map(|o| o.rate))
            .fold(f64::NEG_INFINITY, f64::max);
        if best_other.is_finite() {
            own - best_other
        } else {
            own
        }
    };
    let mut order: Vec<usize> = (0..first.objects.len()).collect();
    order.sort_by(|&a, &b| {
        margin(b)
            .total_cmp(&margin(a))
            .then(first.objects[b].rate.total_cmp(&first.objects[a].rate))
            .then(a.cmp(&b))
    });
    order
}

/// Checks that every agent was evaluated on the same objects, in the same order (as
/// `grasp eval` does): the bar groups compare like with like.
fn check_same_objects(results: &[AgentResult]) -> Result<(), String> {
    let Some(first) = results.first() else {
        return Err("no agents to plot".into());
    };
    if first.objects.is_empty() {
        return Err("no objects to plot".into());
    }
    for r in &results[1..] {
        let same = r.objects.len() == first.objects.len()
            && r.objects
                .iter()
                .zip(&first.objects)
                .all(|(a, b)| a.object == b.object);
        if !same {
            return Err(format!(
                "agent '{}' was evaluated on other objects than '{}'",
                r.agent, first.agent
            ));
        }
    }
    Ok(())
}

/// A short description of the trials per object: "20 trials" or "4-20 trials".
pub fn trials_label(results: &[AgentResult]) -> String {
    let n = results
        .iter()
        .flat_map(|r| r.objects.iter().map(|o| o.trials));
    let (lo, hi) = n.fold((usize::MAX, 0), |(lo, hi), t| (lo.min(t), hi.max(t)));
    match (lo, hi) {
        (usize::MAX, _) => "no trials".into(),
        (lo, hi) if lo == hi => format!("{hi} trial{}", if hi == 1 { "" } else { "s" }),
        (lo, hi) => format!("{lo}-{hi} trials"),
    }
}

/// One row of bars: its label and, per agent, (rate, Wilson low, Wilson high).
struct Row {
    label: String,
    bars: Vec<(f64, f64, f64)>,
}

/// Renders the per-object plot of `results` as SVG text. The title is `title` followed by
/// the number of objects and trials. Errors: no agents, no objects, or agents evaluated on
/// different objects.
pub fn per_object_svg(title: &str, results: &[AgentResult]) -> Result<String, String> {
    check_same_objects(results)?;
    let first = &results[0];
    let k = results.len();
    let mut rows = vec![Row {
        label: "mean (all trials)".into(),
        bars: results
            .iter()
            .map(|r| (r.mean_rate, r.ci95.0, r.ci95.1))
            .collect(),
    }];
    for i in object_order(results) {
        rows.push(Row {
            label: first.objects[i].object.clone(),
            bars: results
                .iter()
                .map(|r| {
                    let o = &r.objects[i];
                    (o.rate, o.ci95.0, o.ci95.1)
                })
                .collect(),
        });
    }
    // Geometry: each bar `bar_px` high, `gap_px` between groups.
    let bar_px = (30 / k as u32).clamp(4, 10);
    let gap_px = 10;
    let group_px = k as u32 * bar_px + gap_px;
    let header_px = 44 + 22 * k as u32;
    let axes_px = 2 * 44 + 24;
    let height = header_px + axes_px + group_px * rows.len() as u32;
    let longest = rows
        .iter()
        .map(|r| r.label.chars().count())
        .max()
        .unwrap_or(4);
    let label_px = (8 * longest as u32 + 20).max(80);
    let full_title = format!(
        "{title} ({} objects x {})",
        first.objects.len(),
        trials_label(results)
    );

    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (WIDTH, height)).into_drawing_area();
        let draw = || -> Result<(), Box<dyn std::error::Error>> {
            root.fill(&WHITE)?;
            let (header, body) = root.split_vertically(header_px);
            // Title and legend: each agent's colour, name, mean and interval.
            header.draw(&Text::new(
                full_title.clone(),
                (WIDTH as i32 / 2, 10),
                ("sans-serif", 22)
                    .into_font()
                    .color(&BLACK)
                    .pos(Pos::new(HPos::Center, VPos::Top)),
            ))?;
            for (j, r) in results.iter().enumerate() {
                let y = 44 + 22 * j as i32;
                let c = PALETTE[j % PALETTE.len()];
                header.draw(&Rectangle::new(
                    [(label_px as i32, y), (label_px as i32 + 26, y + 14)],
                    c.filled(),
                ))?;
                header.draw(&Text::new(
                    format!(
                        "{}: mean {:.1} % (95 % CI {:.1}-{:.1})",
                        r.agent,
                        100.0 * r.mean_rate,
                        100.0 * r.ci95.0,
                        100.0 * r.ci95.1
                    ),
                    (label_px as i32 + 34, y + 7),
                    ("sans-serif", LABEL_FONT)
                        .into_font()
                        .color(&BLACK)
                        .pos(Pos::new(HPos::Left, VPos::Center)),
                ))?;
            }
            let n = rows.len() as f64;
            let mut chart = ChartBuilder::on(&body)
                .margin_right(24)
                .margin_top(4)
                .margin_bottom(8)
                .set_label_area_size(LabelAreaPosition::Top, 44)
                .set_label_area_size(LabelAreaPosition::Bottom, 44)
                .set_label_area_size(LabelAreaPosition::Left, label_px)
                .build_cartesian_2d(0f64..100f64, 0f64..n)?;
            chart
                .configure_mesh()
                .disable_y_mesh()
                .y_labels(0)
                .x_labels(11)
                .x_label_formatter(&|v| format!("{v:.0}"))
                .x_desc("success rate (%), bars: Wilson 95 % intervals")
                .x_label_style(("sans-serif", 15))
                .axis_desc_style(("sans-serif", 16))
                .light_line_style(WHITE.mix(0.0))
                .bold_line_style(BLACK.mix(0.12))
                .draw()?;
            // Row r occupies [n - r - 1, n - r) in y; bars fill it but for the gap.
            let unit = 1.0 / group_px as f64;
            for (ri, row) in rows.iter().enumerate() {
                let top = n - ri as f64 - gap_px as f64 / 2.0 * unit;
                if ri % 2 == 1 {
                    // A light band behind every other object, to guide the eye.
                    chart.draw_series(std::iter::once(Rectangle::new(
                        [(0.0, n - ri as f64), (100.0, n - ri as f64 - 1.0)],
                        BLACK.mix(0.035).filled(),
                    )))?;
                }
                for (j, &(rate, lo, hi)) in row.bars.iter().enumerate() {
                    let c = PALETTE[j % PALETTE.len()];
                    let y1 = top - j as f64 * bar_px as f64 * unit;
                    let y0 = y1 - bar_px as f64 * unit;
                    let ym = (y0 + y1) / 2.0;
                    chart.draw_series(std::iter::once(Rectangle::new(
                        [(0.0, y0), (100.0 * rate, y1)],
                        c.mix(0.85).filled(),
                    )))?;
                    let cap = 0.3 * bar_px as f64 * unit;
                    let whisker = BLACK.mix(0.75).stroke_width(1);
                    chart.draw_series([
                        PathElement::new(vec![(100.0 * lo, ym), (100.0 * hi, ym)], whisker),
                        PathElement::new(
                            vec![(100.0 * lo, ym - cap), (100.0 * lo, ym + cap)],
                            whisker,
                        ),
                        PathElement::new(
                            vec![(100.0 * hi, ym - cap), (100.0 * hi, ym + cap)],
                            whisker,
                        ),
                    ])?;
                }
                // The object's name, right-aligned left of the axis, at the group's centre.
                let (x, y) = chart.backend_coord(&(0.0, n - ri as f64 - 0.5));
                let font = if ri == 0 {
                    ("sans-serif", LABEL_FONT)
                        .into_font()
                        .style(FontStyle::Bold)
                } else {
                    ("sans-serif", LABEL_FONT).into_font()
                };
                root.draw(&Text::new(
                    row.label.clone(),
                    (x - 8, y),
                    font.color(&BLACK).pos(Pos::new(HPos::Right, VPos::Center)),
                ))?;
            }
            // The mean group is set apart from the objects by a line.
            chart.draw_series(std::iter::once(PathElement::new(
                vec![(0.0, n - 1.0), (100.0, n - 1.0)],
                BLACK.mix(0.6).stroke_width(1),
            )))?;
            root.present()?;
            Ok(())
        };
        draw().map_err(|e| e.to_string())?;
    }
    Ok(svg)
}

/// Checks, before an evaluation starts, that `path` can take the plot: an `.svg` name, not
/// a folder itself, that [`crate::util::fsx::check_writable_file`] accepts.
pub fn check_plot_path(path: &Path) -> Result<(), EvalError> {
    let bad = |message: String| EvalError::Plot {
        path: path.to_path_buf(),
        message,
    };
    let is_svg = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("svg"));
    if !is_svg {
        return Err(bad(
            "the plot is written as SVG: the file name must end in .svg".into(),
        ));
    }
    if path.is_dir() {
        return Err(bad("is a folder".into()));
    }
    // The rule of every output file: missing folders are created, an existing file in
    // the way or a folder without write permission is refused now.
    crate::util::fsx::check_writable_file(path).map_err(|e| bad(e.source.to_string()))
}

/// Draws [`per_object_svg`] to `path` (checked by [`check_plot_path`], written
/// atomically).
pub fn write_per_object_plot(
    path: &Path,
    title: &str,
    results: &[AgentResult],
) -> Result<(), EvalError> {
    check_plot_path(path)?;
    let svg = per_object_svg(title, results).map_err(|message| EvalError::Plot {
        path: path.to_path_buf(),
        message,
    })?;
    crate::util::fsx::write_atomic(path, svg.as_bytes()).map_err(|e| EvalError::Plot {
        path: path.to_path_buf(),
        message: e.to_string(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eval::{wilson, ObjectResult};

    fn agent(name: &str, objects: &[(&str, usize)], trials: usize) -> AgentResult {
        let objects: Vec<ObjectResult> = objects
            .iter()
            .map(|&(o, k)| ObjectResult {
                object: o.into(),
                trials,
                successes: k,
                rate: k as f64 / trials as f64,
                ci95: wilson(k, trials),
                mean_steps: 1.0,
                outcomes: (0..trials).map(|t| t < k).collect(),
                deepest_contacts: vec![0.0; trials],
                ..Default::default()
            })
            .collect();
        let k: usize = objects.iter().map(|o| o.successes).sum();
        let n = trials * objects.len();
        AgentResult {
            agent: name.into(),
            mean_rate: objects.iter().map(|o| o.rate).sum::<f64>() / objects.len() as f64,
            ci95: wilson(k, n),
            objects,
            mean_steps: 1.0,
            control_steps_per_s: 1.0,
            wall_s: 1.0,
            ..Default::default()
        }
    }

    #[test]
    fn objects_are_sorted_by_the_first_agents_margin() {
        // Margins of the first agent over the best other: a -2, b +2, c 0, d +2 (but a
        // lower own rate than b).
        let r = [
            agent("p", &[("a", 2), ("b", 4), ("c", 3), ("d", 2)], 4),
            agent("q", &[("a", 4), ("b", 2), ("c", 3), ("d", 0)], 4),
            agent("s", &[("a", 1), ("b", 1), ("c", 1), ("d", 0)], 4),
        ];
        assert_eq!(object_order(&r), vec![1, 3, 2, 0]);
        // A single agent: by its own rate.
        assert_eq!(object_order(&r[..1]), vec![1, 2, 0, 3]);
        assert!(object_order(&[]).is_empty());
    }

    #[test]
    fn svg_names_every_object_and_agent_and_grows_with_the_objects() {
        let names: Vec<String> = (0..61).map(|i| format!("egad_{i}")).collect();
        let objs =
            |k: usize| -> Vec<(&str, usize)> { names.iter().map(|n| (n.as_str(), k)).collect() };
        let r = [
            agent("policy <A&B>", &objs(3), 4),
            agent("Baseline 2", &objs(1), 4),
        ];
        let svg = per_object_svg("train", &r).unwrap();
        assert!(svg.starts_with("<svg"), "{}", &svg[..200]);
        assert!(svg.contains("train (61 objects x 4 trials)"));
        for n in &names {
            assert!(svg.contains(&format!(">\n{n}\n</text>")), "{n} missing");
        }
        // Labels are escaped, so the SVG stays well-formed.
        assert!(svg.contains("policy &lt;A&amp;B&gt;") && svg.contains("Baseline 2: mean 25.0 %"));
        let height = |svg: &str| -> u32 {
            let h = svg.split("height=\"").nth(1).unwrap();
            h[..h.find('"').unwrap()].parse().unwrap()
        };
        let small = per_object_svg("s", &[agent("p", &objs(1)[..19], 20)]).unwrap();
        assert!(
            height(&svg) > 2 * height(&small),
            "{} {}",
            height(&svg),
            height(&small)
        );
    }

    #[test]
    fn mismatched_or_empty_input_is_an_error() {
        let a = agent("p", &[("a", 1), ("b", 1)], 2);
        let b = agent("q", &[("b", 1), ("a", 1)], 2);
        let e = per_object_svg("t", &[a.clone(), b]).unwrap_err();
        assert!(e.contains("'q' was evaluated on other objects"), "{e}");
        assert!(per_object_svg("t", &[]).is_err());
        assert!(per_object_svg("t", &[agent("p", &[], 2)]).is_err());
        assert_eq!(trials_label(&[a]), "2 trials");
    }

    #[test]
    fn plot_paths_are_checked() {
        let dir = tempfile::tempdir().unwrap();
        assert!(check_plot_path(&dir.path().join("p.svg")).is_ok());
        assert!(check_plot_path(&dir.path().join("P.SVG")).is_ok());
        assert!(check_plot_path(Path::new("p.svg")).is_ok());
        let e = check_plot_path(&dir.path().join("p.png")).unwrap_err();
        assert!(e.to_string().contains("must end in .svg"), "{e}");
        // One rule for every output (issue 49): a missing folder is created by the write,
        // a file where a folder goes is refused.
        assert!(check_plot_path(&dir.path().join("no/such/p.svg")).is_ok());
        std::fs::write(dir.path().join("f"), "x").unwrap();
        let e = check_plot_path(&dir.path().join("f/p.svg")).unwrap_err();
        assert!(e.to_string().contains("is a file, not a folder"), "{e}");
        std::fs::create_dir(dir.path().join("d.svg")).unwrap();
        let e = check_plot_path(&dir.path().join("d.svg")).unwrap_err();
        assert!(e.to_string().contains("is a folder"), "{e}");
    }
}
