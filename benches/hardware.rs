//! Speed of the point-cloud pipeline used for the initial grasp: reading a binary PCD,
//! PCA normals (brute-force neighbours) and antipodal candidate sampling.

use criterion::{criterion_group, criterion_main, Criterion};
use grasp::perception::partial_view::sample_box_surface;
use grasp::perception::pointcloud::{
    antipodal_grasps, estimate_normals, AntipodalConfig, PointCloud,
};
use nalgebra::{Point3, Vector3};
use std::hint::black_box;
use std::path::Path;

fn pointcloud(c: &mut Criterion) {
    let fixture = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/clouds/cube_binary.pcd");
    c.bench_function("load binary pcd (1200 points)", |b| {
        b.iter(|| PointCloud::load(black_box(&fixture)).map(|c| c.points.len()))
    });
    let s = sample_box_surface(Point3::origin(), Vector3::new(0.03, 0.03, 0.03), 2000, 1)
        .expect("valid box");
    c.bench_function("normals k=15 (2000 points)", |b| {
        b.iter(|| estimate_normals(black_box(&s.points), 15).map(|n| n.len()))
    });
    let normals = estimate_normals(&s.points, 15).expect("enough points");
    let cfg = AntipodalConfig::default();
    c.bench_function("antipodal 300 samples (2000 points)", |b| {
        b.iter(|| antipodal_grasps(black_box(&s.points), &normals, &cfg).map(|g| g.len()))
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(10)
        .warm_up_time(std::time::Duration::from_millis(500))
        .measurement_time(std::time::Duration::from_secs(2));
    targets = pointcloud
}
criterion_main!(benches);
