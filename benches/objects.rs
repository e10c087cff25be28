//! Object library speed: VHACD decomposition of a non-convex object, cold versus from the
//! hull cache, and generation of the whole `train` set.
//!
//! Run briefly with
//! `cargo bench --bench objects -- --warm-up-time 1 --measurement-time 3`.

use criterion::{criterion_group, criterion_main, Criterion};
use grasp::objects::decomp::{decompose, decompose_cached, DecompParams};
use grasp::objects::sets::{build_all, prepare, resolve_specs, BuildContext};
use std::hint::black_box;

fn decomposition(c: &mut Criterion) {
    let dir = tempfile::tempdir().expect("temp dir");
    let params = DecompParams::default();
    let mut group = c.benchmark_group("decompose");
    group.sample_size(10);
    for name in ["egad_c5_d2", "bottle_tall"] {
        let spec = &resolve_specs(name).expect("built-in")[0];
        let mesh = prepare(spec).expect("prepare").mesh;
        let file = dir.path().join(format!("{name}.hulls.json"));
        // Fill the cache once so the cached case only reads it.
        decompose_cached(&mesh, &params, &file, name).expect("decompose");
        group.bench_function(format!("{name}/cold"), |b| {
            b.iter(|| decompose(black_box(&mesh), &params, name).expect("decompose"))
        });
        group.bench_function(format!("{name}/cached"), |b| {
            b.iter(|| decompose_cached(black_box(&mesh), &params, &file, name).expect("cache"))
        });
    }
    group.finish();
}

fn train_set(c: &mut Criterion) {
    let specs = resolve_specs("train").expect("train set");
    let mut group = c.benchmark_group("train_set");
    group.sample_size(10);
    group.bench_function("generate_61_meshes", |b| {
        b.iter(|| {
            specs
                .iter()
                .map(|s| prepare(s).expect("prepare"))
                .collect::<Vec<_>>()
        })
    });
    let dir = tempfile::tempdir().expect("temp dir");
    let ctx = BuildContext::with_cache_dir(dir.path());
    build_all(&specs, &ctx).expect("fill cache");
    group.bench_function("load_61_objects_warm_cache", |b| {
        b.iter(|| build_all(black_box(&specs), &ctx).expect("build"))
    });
    group.finish();
}

criterion_group!(benches, decomposition, train_set);
criterion_main!(benches);
