//! `grasp eval --plot`: the per-object plot of every agent (Table I as a picture), drawn
//! from a live evaluation and again from its saved `--json` output, and its errors.

use std::path::Path;

#[path = "common/cli.rs"]
mod cli;
use cli::*;

/// How often `s` is the whole content of a text element of `svg`.
fn texts(svg: &str, s: &str) -> usize {
    svg.matches(&format!(">{s}</text>")).count() + svg.matches(&format!(">\n{s}\n</text>")).count()
}

/// A small well-formedness check of XML: every tag closed in order, attributes quoted,
/// no bare '&' or '<' in text.
fn assert_well_formed(xml: &str) {
    let mut stack: Vec<String> = Vec::new();
    let mut rest = xml;
    while let Some(open) = rest.find('<') {
        let text = &rest[..open];
        for (i, _) in text.match_indices('&') {
            let entity = &text[i..];
            assert!(
                ["&lt;", "&gt;", "&amp;", "&quot;", "&apos;", "&#"]
                    .iter()
                    .any(|e| entity.starts_with(e)),
                "bare & in text: {}",
                &entity[..entity.len().min(30)]
            );
        }
        let close = rest[open..].find('>').expect("an unclosed tag") + open;
        let tag = &rest[open + 1..close];
        assert!(!tag.contains('<'), "'<' inside a tag: {tag}");
        assert_eq!(tag.matches('"').count() % 2, 0, "unbalanced quotes: {tag}");
        if tag.starts_with('?') || tag.starts_with('!') {
        } else if let Some(name) = tag.strip_prefix('/') {
            let top = stack
                .pop()
                .unwrap_or_else(|| panic!("</{name}> closes nothing"));
            assert_eq!(top, name.trim(), "</{name}> closes <{top}>");
        } else if !tag.ends_with('/') {
            stack.push(tag.split_whitespace().next().unwrap_or("").to_string());
        }
        rest = &rest[close + 1..];
    }
    assert!(stack.is_empty(), "unclosed elements: {stack:?}");
}

#[test]
fn the_plot_shows_every_agent_and_object_and_redraws_from_the_json() {
    let dir = tempfile::tempdir().unwrap();
    let live = dir.path().join("live.svg");
    let o = grasp(&[
        "--json",
        "eval",
        "--policy",
        "baseline1,baseline2",
        "--objects",
        "box_sugar,can_soup",
        "--trials",
        "1",
        "--plot",
        live.to_str().unwrap(),
        "--plot-title",
        "Two objects",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let svg = std::fs::read_to_string(&live).unwrap();
    assert!(svg.starts_with("<svg"), "{}", &svg[..100]);
    assert_well_formed(&svg);
    assert!(svg.contains("Two objects (2 objects x 1 trial)"), "{svg}");
    // One bar group per object, labelled once, and the group of the means.
    for label in ["box_sugar", "can_soup", "mean (all trials)"] {
        assert_eq!(texts(&svg, label), 1, "{label}");
    }
    // Every agent named in the legend with its mean and interval.
    for agent in ["Baseline 1: mean", "Baseline 2: mean"] {
        assert_eq!(svg.matches(agent).count(), 1, "{agent}");
    }
    assert!(svg.contains("95 % CI"));

    // The saved JSON draws the same picture, and picks and renames agents.
    let json = dir.path().join("eval.json");
    std::fs::write(&json, &o.stdout).unwrap();
    let again = dir.path().join("again.svg");
    let o = grasp(&[
        "-q",
        "eval",
        "--from-json",
        json.to_str().unwrap(),
        "--plot",
        again.to_str().unwrap(),
        "--plot-title",
        "Two objects",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(std::fs::read_to_string(&again).unwrap(), svg);
    let picked = dir.path().join("picked.SVG");
    let o = grasp(&[
        "eval",
        "--from-json",
        json.to_str().unwrap(),
        "--policy",
        "baseline2",
        "--labels",
        "B2 <scripted>",
        "--plot",
        picked.to_str().unwrap(),
        "--markdown",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.starts_with("| agent | box_sugar | can_soup |"), "{out}");
    assert!(
        out.contains("| B2 <scripted> |") && !out.contains("Baseline 1"),
        "{out}"
    );
    let svg = std::fs::read_to_string(&picked).unwrap();
    assert_well_formed(&svg);
    assert!(svg.contains("B2 &lt;scripted&gt;: mean") && !svg.contains("Baseline 1"));
    assert!(svg.contains(&format!("Per-object success, {}", json.display())));
}

#[test]
fn plot_errors_are_clear_and_come_before_the_evaluation() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().to_str().unwrap();
    let eval = |plot: &str| eval_one(&["--plot", plot]);
    let png = format!("{d}/p.png");
    let o = eval(&png);
    assert_fails(&o, &["p.png", "must end in .svg"]);
    assert!(!stderr(&o).contains("evaluating"), "{}", stderr(&o));
    // One rule for every output (issue 49): a missing folder is created, a file where a
    // folder goes is refused.
    std::fs::write(dir.path().join("f"), "x").unwrap();
    assert_fails(
        &eval(&format!("{d}/f/p.svg")),
        &["p.svg", "is a file, not a folder"],
    );
    std::fs::create_dir(dir.path().join("d.svg")).unwrap();
    assert_fails(&eval(&format!("{d}/d.svg")), &["d.svg", "is a folder"]);

    // Saved results: a missing or foreign file, an unknown agent, a wrong label count.
    let o = grasp(&["eval", "--from-json", "/nonexistent/eval.json"]);
    assert_fails(&o, &["/nonexistent/eval.json"]);
    let foreign = dir.path().join("f.json");
    std::fs::write(&foreign, "{\"agent\": 1}").unwrap();
    let o = grasp(&["eval", "--from-json", foreign.to_str().unwrap()]);
    assert_fails(&o, &["f.json", "not the JSON of `grasp eval --json`"]);
    let saved = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("docs/results/recipe_2026_12/eval_unseen_20.json");
    let saved = saved.to_str().unwrap();
    let o = grasp(&["eval", "--from-json", saved, "--policy", "nosuch"]);
    assert_fails(&o, &["no agent 'nosuch'", "Baseline 1"]);
    let o = grasp(&["eval", "--from-json", saved, "--labels", "a,b"]);
    assert_fails(&o, &["--labels names 2 agents, but there are 5"]);
    // --from-json replaces the evaluation: its flags are refused.
    let o = grasp(&["eval", "--from-json", saved, "--trials", "3"]);
    assert_fails_with(&o, 2, &["--trials"]);
}

#[test]
fn the_saved_unseen_evaluation_plots_at_19_objects() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("unseen.svg");
    let saved = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("docs/results/recipe_2026_12/eval_unseen_20.json");
    let o = grasp(&[
        "-q",
        "eval",
        "--from-json",
        saved.to_str().unwrap(),
        "--policy",
        "runs/ship_new/checkpoints/latest,baseline1,baseline2",
        "--plot",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    // The printed means are Table I's.
    assert!(
        text.contains("mean success 73.4 % (95 % CI 68.8-77.6)"),
        "{text}"
    );
    assert!(
        text.contains("Baseline 2: mean success 52.1 % (95 % CI 47.1-57.1)"),
        "{text}"
    );
    let svg = std::fs::read_to_string(&out).unwrap();
    assert_well_formed(&svg);
    assert!(svg.contains("(19 objects x 20 trials)"));
    for object in ["prism_hex", "spatula", "egad_u5_c6_d3", "capsule_pill"] {
        assert_eq!(texts(&svg, object), 1, "{object}");
    }
}

#[test]
fn saved_seeds_pool_into_one_evaluation_with_its_paired_test_and_plot() {
    let d = "docs/results/pregrasp_views_2026_12";
    let files = format!(
        "{d}/unseen_antipodal_seed0.json,{d}/unseen_antipodal_seed1.json,{d}/unseen_antipodal_seed2.json"
    );
    let dir = tempfile::tempdir().unwrap();
    let svg = dir.path().join("pooled.svg");
    let o = grasp(&[
        "eval",
        "--from-json",
        &files,
        "--policy",
        "pca8,b1",
        "--plot",
        svg.to_str().unwrap(),
    ]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", stderr(&o));
    // The three seeds' trials of the 8-synergy agent and baseline 1, 60 per object.
    assert!(out.contains("pca8: mean success 97.7 %"), "{out}");
    assert!(out.contains("b1: mean success 90.2 %"), "{out}");
    assert!(
        out.contains(
            "pca8 vs b1 on identical start poses: only the first won 98 trials, only the second 12"
        ),
        "{out}"
    );
    assert!(out.contains("/60"), "{out}");
    let plot = std::fs::read_to_string(&svg).unwrap();
    assert_well_formed(&plot);
    assert!(plot.contains("60 trials"), "{plot}");
    // Files that recorded the lifts' turns: the held lifts' median pooled, the failed
    // lifts' left to each file.
    let r = "docs/results/squeeze_2026_12/report";
    let o = grasp(&[
        "eval",
        "--from-json",
        &format!("{r}/novel_top-down_seed0.json,{r}/novel_top-down_seed1.json"),
    ]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        out.contains("deg in the lifts that held it (the failed lifts' median is in each file)"),
        "{out}"
    );

    // Seeds that would not pair are refused, naming the file.
    let twice = format!("{d}/unseen_antipodal_seed0.json,{d}/unseen_antipodal_seed0.json");
    let o = grasp(&["eval", "--from-json", &twice]);
    assert_fails(&o, &["unseen_antipodal_seed0.json", "seed 0 twice"]);
    let mixed = format!(
        "{d}/unseen_antipodal_seed0.json,docs/results/fig5_2026_12/pca8/unseen_top-down_seed1.json"
    );
    let o = grasp(&["eval", "--from-json", &mixed, "--policy", "pca8"]);
    assert_fails(
        &o,
        &["unseen_top-down_seed1.json", "placement top-down here"],
    );
    let o = grasp(&["eval", "--from-json", &files, "--policy", "nobody"]);
    assert_fails(&o, &["the files hold no agent 'nobody'", "pca8"]);
}
