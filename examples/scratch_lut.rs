use spectral_skin::evaluate::Prepared;
use spectral_skin::maps::lut::*;
use spectral_skin::*;
use std::time::Instant;
fn main() {
    let prepared = Prepared::new(&Request::new(Outputs::material())).unwrap();
    for (m, b, h) in [(33, 9, 13), (33, 7, 17), (33, 9, 17), (41, 11, 17)] {
        let res = TableResolution { melanin: m, melanin_blend: b, hemoglobin: h };
        let t = Instant::now();
        let table = MaterialTable::build(&prepared, res).unwrap();
        let build = t.elapsed().as_secs_f64();
        let err = measure_error(&table, &prepared, 1000).unwrap();
        println!("{m}x{b}x{h} ({} nodes): build {build:.2}s  albedo {:.4}%  radius {:.4}%  rw base {:.4}%", res.node_count(), 100.0*err.max_albedo_relative, 100.0*err.max_radius_relative, 100.0*err.max_random_walk_base_color_relative);
    }
}
