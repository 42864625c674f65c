#[path = "../tests/common/earcut_fixtures.rs"]
mod earcut_fixtures;
fn main() {
    let name = std::env::args().nth(1).unwrap();
    let reps: usize = std::env::args().nth(2).unwrap().parse().unwrap();
    let (coords, holes) = earcut_fixtures::flat(&earcut_fixtures::fixture(&name));
    let mut t = indra::geometry::triangulate::Triangulator::new();
    let mut out = Vec::new();
    let which = std::env::args().nth(3).unwrap_or_default();
    let start = std::time::Instant::now();
    if which != "earcut" { for _ in 0..reps { out.clear(); t.flat(&coords, &holes, &mut out).unwrap(); } }
    println!("{name}: {} triangles, {:.1} us", out.len() / 3, start.elapsed().as_secs_f64() * 1e6 / reps as f64);
    let mut e = earcut::Earcut::new();
    let pts: Vec<[f64;2]> = coords.chunks_exact(2).map(|p| [p[0], p[1]]).collect();
    let h: Vec<u32> = holes.iter().map(|&x| x as u32).collect();
    let mut o: Vec<u32> = Vec::new();
    let start = std::time::Instant::now();
    if which != "indra" { for _ in 0..reps { e.earcut(pts.iter().copied(), &h, &mut o); } }
    if which.is_empty() {
        let (a, b) = (norm(&out), norm(&o));
        let common = a.iter().filter(|t| b.binary_search(t).is_ok()).count();
        let only: Vec<_> = a.iter().filter(|t| b.binary_search(t).is_err()).collect();
        if std::env::var_os("SHOW").is_some() { println!("ours only {only:?}\nholes {holes:?}"); }
        println!("same triangles: {common} of {} / {}; first ours {:?} earcut {:?}", a.len(), b.len(), &out[..6], &o[..6]);
    }
    println!("earcut: {} triangles, {:.1} us", o.len() / 3, start.elapsed().as_secs_f64() * 1e6 / reps as f64);
}
#[allow(dead_code)]
fn norm(t: &[u32]) -> Vec<[u32; 3]> {
    let mut v: Vec<[u32; 3]> = t.chunks_exact(3).map(|c| {
        let m = (0..3).min_by_key(|&i| c[i]).unwrap();
        [c[m], c[(m + 1) % 3], c[(m + 2) % 3]]
    }).collect();
    v.sort();
    v
}
