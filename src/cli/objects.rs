//! `grasp objects`: list, inspect and export the objects of a set.

use super::Global;
use anyhow::{bail, Context};
use clap::{Args, Subcommand};
use grasp::objects::sets::{self, BuildContext, ResolvedSpec};
use grasp::objects::spec::ShapeSpec;
use grasp::objects::stream;
use grasp::objects::{HullSource, Object, ObjectError};
use grasp::util::fsx::{check_outputs, Named};
use std::path::{Path, PathBuf};

/// Inspect the object library: built-in sets (`train`, `unseen`, `all`), the procedural
/// training stream (`procedural`, objects `proc-<seed>-<index>`), folders of OBJ/STL
/// meshes, manifests, or comma-separated built-in names.
#[derive(Debug, Args)]
#[command(after_help = "Examples:
  grasp objects list --set train
  grasp objects list --set ./my_meshes --json
  grasp objects list --set procedural --count 20 --stream-seed 3
  grasp objects export proc-3-17 --out proc-3-17.obj
  grasp objects show bottle_tall
  grasp objects show mug --set objects.toml
  grasp objects export egad_c3_d2 --out egad_c3_d2.obj

Convex decompositions are cached in $GRASP_CACHE_DIR (default ~/.cache/grasp) and, for
user meshes, next to the mesh file (<mesh>.hulls.json).")]
pub struct ObjectsArgs {
    #[command(subcommand)]
    cmd: ObjectsCmd,
}

#[derive(Debug, Subcommand)]
enum ObjectsCmd {
    /// List the objects of a set: name, kind, size, mass, hull count.
    List {
        /// train | unseen | all | procedural | DIR | manifest.toml | mesh.obj | name,name,...
        #[arg(long = "set", visible_alias = "objects", default_value = "all")]
        set: String,
        /// With `--set procedural`: how many stream objects to list (1..=10000; default
        /// 64, the objects `--objects procedural` means everywhere).
        #[arg(long)]
        count: Option<usize>,
        /// With `--set procedural`: the stream seed to list (default 0, the seed of
        /// `--objects procedural` everywhere; the global --seed seeds episodes, never
        /// objects).
        #[arg(long)]
        stream_seed: Option<u64>,
    },
    /// Show one object: size, bounding box, mass, volume, friction, inertia, hulls.
    Show {
        /// Object name (or a path to a mesh file).
        name: String,
        /// Set to look the name up in.
        #[arg(long = "set", visible_alias = "objects", default_value = "all")]
        set: String,
    },
    /// Write an object's visual mesh (object frame, metres) as OBJ or binary STL.
    Export {
        /// Object name (or a path to a mesh file).
        name: String,
        /// Output .obj or .stl file (by its extension); `-` writes the OBJ text to stdout.
        #[arg(long)]
        out: PathBuf,
        /// Set to look the name up in.
        #[arg(long = "set", visible_alias = "objects", default_value = "all")]
        set: String,
    },
}

/// Finds object `name` in set `set`; a `name` that is an existing mesh file stands alone.
/// A stream object (`proc-<seed>-<index>`) is found in the sets `all` (the default) and
/// `procedural` (the endless stream); another set must hold it.
fn find_spec(name: &str, set: &str) -> anyhow::Result<ResolvedSpec> {
    if let Some((seed, index)) = stream::parse_name(name) {
        if set == "all" || set == stream::STREAM_SET {
            return Ok(stream::stream_spec(seed, index));
        }
    }
    let specs = sets::resolve_specs(set).with_context(|| format!("cannot resolve set `{set}`"))?;
    if let Some(s) = specs.iter().find(|s| s.spec.name == name) {
        return Ok(s.clone());
    }
    if Path::new(name).is_file() {
        let mut v = sets::resolve_specs(name).with_context(|| format!("cannot load `{name}`"))?;
        if v.len() == 1 {
            return Ok(v.remove(0));
        }
        bail!(
            "{name} holds {} objects; name one with --set {name}",
            v.len()
        );
    }
    let mut msg = format!("no object `{name}` in set `{set}`");
    let sugg: Vec<String> = {
        let mut close = sets::suggest(name);
        close.retain(|c| specs.iter().any(|s| &s.spec.name == c));
        close
    };
    if !sugg.is_empty() {
        msg.push_str(&format!("; did you mean {}?", sugg.join(", ")));
    } else {
        msg.push_str("; `grasp objects list` shows the names");
    }
    bail!(msg)
}

/// Most stream objects `objects list --count` builds.
const MAX_COUNT: usize = 10_000;

#[derive(serde::Serialize)]
struct Summary<'a> {
    name: &'a str,
    kind: String,
    size_cm: [f64; 3],
    mass_g: f64,
    hulls: usize,
    hull_source: HullSource,
}

fn cm(v: [f64; 3]) -> [f64; 3] {
    v.map(|x| (x * 1000.0).round() / 10.0)
}

/// Runs `grasp objects`.
pub fn run(args: ObjectsArgs, global: &Global) -> anyhow::Result<()> {
    match args.cmd {
        ObjectsCmd::List {
            set,
            count,
            stream_seed,
        } => {
            let objects = if set == stream::STREAM_SET {
                if global.seed.is_some() {
                    bail!(
                        "--seed seeds episodes, not objects: `procedural` is stream seed 0 \
                         everywhere (as in `eval --objects procedural`); list another stream \
                         seed with --stream-seed S"
                    );
                }
                let seed = stream_seed.unwrap_or(0);
                let n = count.unwrap_or(stream::DEFAULT_COUNT);
                if n == 0 || n > MAX_COUNT {
                    bail!(
                        "--count {n} must be in 1..={MAX_COUNT} (each object is built to be \
                         listed; `grasp objects show proc-<seed>-<index>` shows any one)"
                    );
                }
                sets::build_all(&stream::stream_specs(seed, n), &BuildContext::from_env())
                    .with_context(|| format!("cannot build the procedural stream (seed {seed})"))?
            } else {
                if count.is_some() || stream_seed.is_some() {
                    bail!("--count and --stream-seed apply to --set procedural only");
                }
                super::load_objects(&set)?
            };
            let rows: Vec<Summary> = objects
                .iter()
                .map(|o| Summary {
                    name: &o.name,
                    kind: o.kind.to_string(),
                    size_cm: cm(o.size()),
                    mass_g: (o.mass_kg * 10000.0).round() / 10.0,
                    hulls: o.hulls.len(),
                    hull_source: o.hull_source,
                })
                .collect();
            if global.json {
                println!("{}", serde_json::to_string_pretty(&rows)?);
            } else {
                println!(
                    "{:<16} {:<14} {:>20} {:>8} {:>6}",
                    "name", "kind", "size x*y*z (cm)", "mass g", "hulls"
                );
                for r in &rows {
                    let s = r.size_cm;
                    println!(
                        "{:<16} {:<14} {:>20} {:>8.1} {:>6}",
                        r.name,
                        r.kind,
                        format!("{:.1}x{:.1}x{:.1}", s[0], s[1], s[2]),
                        r.mass_g,
                        r.hulls
                    );
                }
                println!("{} objects", rows.len());
            }
        }
        ObjectsCmd::Show { name, set } => {
            let spec = find_spec(&name, &set)?;
            let ctx = BuildContext::from_env();
            let obj = sets::build(&spec, &ctx)
                .with_context(|| format!("cannot build object `{}`", spec.spec.name))?;
            if global.json {
                println!("{}", serde_json::to_string_pretty(&obj)?);
            } else {
                print_object(&obj);
            }
        }
        ObjectsCmd::Export { name, out, set } => {
            let spec = find_spec(&name, &set)?;
            if out.as_os_str() != "-" {
                // The export never replaces the mesh (or manifest) it reads.
                let mut inputs = Vec::new();
                if let ShapeSpec::Mesh { path, .. } = &spec.spec.shape {
                    inputs.push(Named::new("the object's mesh", path));
                }
                for (flag, p) in [("NAME", Path::new(&name)), ("--set", Path::new(&set))] {
                    if p.is_file() {
                        inputs.push(Named::new(flag, p));
                    }
                }
                check_outputs(&inputs, &[Named::new("--out", &out)], &[])?;
            }
            let prepared = sets::prepare(&spec)
                .with_context(|| format!("cannot build object `{}`", spec.spec.name))?;
            let comment = format!(
                "grasp object {} ({}), object frame: metres, z up, origin at the bottom centre",
                spec.spec.name, spec.spec.kind
            );
            if out.as_os_str() == "-" {
                // `--out -`: the OBJ text on stdout, nothing else.
                use std::io::Write;
                let mut stdout = std::io::stdout().lock();
                stdout
                    .write_all(prepared.mesh.to_obj_string(&comment).as_bytes())
                    .and_then(|()| stdout.flush())
                    .context("writing the OBJ to stdout")?;
                return Ok(());
            }
            let ext = out
                .extension()
                .map(|e| e.to_string_lossy().to_ascii_lowercase());
            let written = match ext.as_deref() {
                Some("obj") => prepared.mesh.write_obj(&out, &comment),
                Some("stl") => prepared.mesh.write_stl(&out),
                _ => bail!(
                    "cannot export to {}: the file must end in .obj or .stl (or be `-` for \
                     OBJ on stdout)",
                    out.display()
                ),
            };
            written
                .map_err(|e: ObjectError| anyhow::anyhow!(e))
                .with_context(|| format!("cannot export to {}", out.display()))?;
            if global.json {
                println!(
                    "{}",
                    serde_json::json!({
                        "name": spec.spec.name,
                        "out": out.display().to_string(),
                        "vertices": prepared.mesh.vertices.len(),
                        "triangles": prepared.mesh.triangles.len(),
                    })
                );
            } else if !global.quiet {
                println!(
                    "wrote {} ({} vertices, {} triangles)",
                    out.display(),
                    prepared.mesh.vertices.len(),
                    prepared.mesh.triangles.len()
                );
            }
        }
    }
    Ok(())
}

fn print_object(o: &Object) {
    let s = cm(o.size());
    println!("name       {}", o.name);
    println!("kind       {}", o.kind);
    println!("size       {:.1} x {:.1} x {:.1} cm", s[0], s[1], s[2]);
    println!(
        "bbox       min {:?} max {:?} m (z up, origin at the bottom centre)",
        o.bbox.min.map(|x| (x * 1e4).round() / 1e4),
        o.bbox.max.map(|x| (x * 1e4).round() / 1e4)
    );
    println!("mass       {:.1} g", o.mass_kg * 1000.0);
    println!("volume     {:.1} cm^3", o.volume_m3 * 1e6);
    println!(
        "density    {:.0} kg/m^3 (effective)",
        o.mass_kg / o.volume_m3
    );
    println!("friction   {}", o.friction);
    println!(
        "com        [{:.4}, {:.4}, {:.4}] m",
        o.com[0], o.com[1], o.com[2]
    );
    println!(
        "inertia    diag [{:.3e}, {:.3e}, {:.3e}] kg m^2",
        o.inertia[0][0], o.inertia[1][1], o.inertia[2][2]
    );
    if let Some(p) = o.primitive {
        println!("primitive  {p:?}");
    }
    let pts: Vec<usize> = o.hulls.iter().map(|h| h.points.len()).collect();
    println!(
        "hulls      {} ({:?}), points per hull {:?}",
        o.hulls.len(),
        o.hull_source,
        pts
    );
    println!(
        "mesh       {} vertices, {} triangles",
        o.mesh.vertices.len(),
        o.mesh.triangles.len()
    );
}
