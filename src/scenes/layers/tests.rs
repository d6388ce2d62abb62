use std::collections::BTreeMap;

use super::measure::{parse_log, parse_solids, passes, steady_layer, Grain, PassLine};
use super::settings::{with_own, LayersSettings};
use super::*;
use crate::scene::settings::SceneSettings;
use crate::scene::{LAYER_FRACTION_MAX, MIN_INSERT_VOLUME};

fn settings() -> SceneSettings {
    LayersSettings { layers: 4, plate_diameters: 20.0, blade_clearance_mm: 0.05, ..LayersSettings::default() }
        .settings()
}

fn values(pairs: &[(&str, f64)]) -> BTreeMap<String, f64> {
    pairs.iter().map(|(k, v)| (k.to_string(), *v)).collect()
}

fn scene(s: &SceneSettings) -> Scene {
    let v =
        values(&[("diameter", 0.065), ("layer_thickness", 0.1), ("blade_speed", 0.1), ("density", 4386.0)]);
    crate::scenes::build(&v, s).unwrap()
}

#[test]
fn the_platform_drops_by_the_layer_thickness_before_every_pass() {
    let sc = scene(&settings());
    let plan = plan_of(&sc);
    // Four passes run; the box is built for as many more again, for `sweep extend`.
    assert_eq!((plan.most(), plan.passes.len()), (4, 4 * EXTEND_ROOM));
    for pair in plan.passes.windows(2) {
        assert!((pair[1].top - pair[0].top - 1e-4).abs() < 1e-12, "drop {}", pair[1].top - pair[0].top);
        assert!((pair[1].tip - pair[1].top - 5e-5).abs() < 1e-12, "clearance");
    }
    // The first layer is the drop and the clearance over the bare plate.
    assert!((plan.drop_before(1) - 1.5e-4).abs() < 1e-12);
    assert!((plan.drop_before(2) - 1e-4).abs() < 1e-12);
    // The plate is the length asked for; the blade's tip travels past its end.
    assert!((plan.plate_x1 - plan.plate_x0 - 20.0 * sc.diameter).abs() < 1e-12);
    assert!(plan.tip_x0 + plan.travel > plan.plate_x1);
    // Every pass's top and the feed platform's faces stay inside the box.
    let last = plan.passes.last().unwrap();
    assert!(last.tip + super::part(&sc).blade.blade_top < sc.z_hi);
    assert!(last.top - plan.block_depth > sc.z_lo && last.top - plan.block_depth < 0.0);
}

#[test]
fn the_blade_starts_once_the_dose_is_at_rest_and_at_the_latest_when_the_fixed_wait_ends() {
    let plan = plan_of(&scene(&settings()));
    // At rest for the blade: a hundredth of its speed.
    assert!((plan.rest_speed - DOSE_REST_SHARE * 0.1).abs() < 1e-15);
    // The checks reach the whole fixed fall and wait, and no check further.
    for (checks, most) in [(plan.fall_checks, plan.fall_steps), (plan.wait_checks, plan.wait_steps)] {
        assert!(checks * plan.settle_check_steps >= most, "{checks} checks for {most} steps");
        assert!(checks.saturating_sub(1) * plan.settle_check_steps < most.max(1));
    }
    // A later dose's fall and wait are at most SETTLE_CHECKS checks (the first, taller, more).
    assert!(plan.wait_checks <= SETTLE_CHECKS && plan.fall_checks > 0);
}

#[test]
fn a_round_blade_rides_a_largest_diameter_over_the_feed_platform_and_the_wall() {
    // No clearance: the flat blade's tip runs on the top surface; the round blade's stands the
    // largest diameter (mono: the diameter) over it, the plate still k drops under the tip.
    let flat = with_own(settings(), |l| l.blade_clearance_mm = 0.0);
    let round = with_own(flat.clone(), |l| l.blade_profile = "round".into());
    for (s, gap) in [(&flat, 0.0), (&round, 0.065e-3)] {
        let sc = scene(s);
        let plan = plan_of(&sc);
        assert!((plan.platform_gap - gap).abs() < 1e-12, "{}: {}", own(s).blade_profile, plan.platform_gap);
        for (k, p) in plan.passes.iter().enumerate() {
            assert!((p.tip - (k + 1) as f64 * 1e-4).abs() < 1e-12, "the tip stays k drops over the plate");
            assert!((p.tip - p.top - gap).abs() < 1e-12);
        }
        // The feed platform's faces, lowered with it, stay inside the box.
        assert!(plan.passes[0].top - plan.block_depth > sc.z_lo);
    }
    // A clearance of at least the largest diameter is kept as it is.
    let wide = with_own(round, |l| l.blade_clearance_mm = 0.1);
    assert!((plan_of(&scene(&wide)).platform_gap - 1e-4).abs() < 1e-12);
}

/// The volume of a pass's dose region once shrunk by the largest diameter on every side, as
/// LIGGGHTS measures it with `all_in yes`.
fn shrunk_dose_region(sc: &Scene) -> f64 {
    let plan = plan_of(sc);
    let d_max = sc.diameter; // mono powder
    (plan.dose_x1 - plan.dose_x0 - d_max) * (sc.depth - d_max) * (plan.dose_height - d_max)
}

#[test]
fn a_fine_powder_in_thin_layers_gets_a_sparser_dose_at_the_same_depth_not_a_wider_box() {
    let at = |d_mm: f64, t_mm: f64| {
        let v = values(&[
            ("diameter", d_mm),
            ("layer_thickness", t_mm),
            ("blade_speed", 0.1),
            ("density", 4430.0),
        ]);
        crate::scenes::build(&v, &settings()).unwrap()
    };
    // 65 µm in 100 µm layers: the dose region is above LIGGGHTS's floor at the default fraction,
    // and falls from rest.
    let coarse = at(0.065, 0.1);
    assert!(shrunk_dose_region(&coarse) > MIN_INSERT_VOLUME);
    let plan = plan_of(&coarse);
    assert_eq!((plan.dose_fraction, plan.dose_speed), (DOSE_FRACTION, 0.0));
    // 24 µm in 30 µm layers: at that fraction the region would be under the floor (LIGGGHTS
    // stops: "Unable to calculate region volume"). The depth stays the default in diameters; the
    // dose is inserted sparser, in a region that reaches the floor exactly, and thrown down.
    let fine = at(0.024, 0.03);
    let r = shrunk_dose_region(&fine);
    assert!(r >= MIN_INSERT_VOLUME * (1.0 - 1e-9), "{r:e}");
    assert!(r <= MIN_INSERT_VOLUME * 1.01, "no more than needed: {r:e}");
    assert!((fine.depth / fine.diameter - coarse.depth / coarse.diameter).abs() < 1.0, "not widened");
    let plan = plan_of(&fine);
    assert!(plan.dose_fraction < DOSE_FRACTION && plan.dose_speed > 0.0);
    // The same number of particles as the fraction asks of the region's whole volume.
    let region = (plan.dose_x1 - plan.dose_x0) * fine.depth * plan.dose_height;
    let inserted = plan.dose_fraction * region / (std::f64::consts::PI / 6.0 * fine.diameter.powi(3));
    assert!(
        (inserted / plan.dose_particles as f64 - 1.0).abs() < 0.15,
        "{inserted} vs {}",
        plan.dose_particles
    );
    // Thrown down, it lands in about the time the dense dose would fall: no pass waits on it.
    assert!(plan.wait_steps < plan.pass_steps, "wait {} pass {}", plan.wait_steps, plan.pass_steps);
}

#[test]
fn a_run_s_files_are_the_dumps_of_its_passes_as_the_deck_writes_them() {
    // The deck dumps pass k's plate as dump.layer.k; an earlier attempt's are removed before a run.
    assert!(TEMPLATE.source.contains("custom 1 dump.layer.{{ p.k }} "));
    let files = Layers.run_files(&settings());
    assert_eq!(files, ["dump.layer.1", "dump.layer.2", "dump.layer.3", "dump.layer.4"]);
    assert_eq!(files[2], measure::layer_dump(3));
}

/// A square lattice of spheres of diameter `d` at height `z` over the plate's inner part, ids
/// from `first`.
fn lattice(sc: &Scene, plan: &Plan, d: f64, z: f64, first: u64) -> Vec<Grain> {
    let nx = ((plan.plate_x1 - plan.plate_x0) / d).floor() as usize;
    let ny = (sc.depth / d).floor() as usize;
    let mut out = Vec::new();
    for i in 0..nx {
        for j in 0..ny {
            out.push(Grain {
                id: first + (i * ny + j) as u64,
                x: plan.plate_x0 + (i as f64 + 0.5) * d,
                y: (j as f64 + 0.5) * sc.depth / ny as f64,
                z,
                r: 0.5 * d,
            });
        }
    }
    out
}

#[test]
fn a_second_layer_on_the_first_is_measured_as_its_own_deposit_and_cover() {
    let sc = scene(&settings());
    let plan = plan_of(&sc);
    let d = sc.diameter;
    let first = lattice(&sc, &plan, d, 0.5 * d, 1);
    let mut both = first.clone();
    both.extend(lattice(&sc, &plan, d, 1.5 * d, 10_000));
    let m = sc.material.density * std::f64::consts::PI / 6.0 * d.powi(3);
    let lines = [
        PassLine { k: 1, step: 10, plate_mass: first.len() as f64 * m },
        PassLine { k: 2, step: 20, plate_mass: both.len() as f64 * m },
    ];
    let recs = passes(&sc, &plan, &lines, &[], &[first.clone(), both.clone()]);
    let sphere_volume = std::f64::consts::PI / 6.0 * d.powi(3);
    let expected = first.len() as f64 * sphere_volume / plan.plate_area;
    for r in &recs {
        assert!((r.deposit_m - expected).abs() < 1e-12 * expected.max(1.0), "pass {} deposit", r.k);
        assert_eq!(r.particles, first.len());
    }
    // The second pass's relative density is its deposit over one drop, the first's over the
    // drop and the clearance.
    assert!((recs[1].relative_density - expected / 1e-4).abs() < 1e-9);
    assert!((recs[0].relative_density - expected / 1.5e-4).abs() < 1e-9);
    // Touching spheres on a square lattice cover π/4 of the plane; a grid of D/4 samples it to
    // within a few per cent.
    let quarter_pi = std::f64::consts::FRAC_PI_4;
    assert!(recs.iter().all(|r| (r.covered_fraction - quarter_pi).abs() < 0.03), "covered {recs:?}");
    // The second pass met the first one's top: the tip over its mean surface (centres to tops).
    let tip = plan.passes[1].tip;
    assert!(recs[1].effective_thickness_m > tip - d && recs[1].effective_thickness_m < tip - 0.5 * d);
    assert!((recs[0].effective_thickness_m - plan.passes[0].tip).abs() < 1e-15);
    // A sphere in flight high over the plate as a pass is measured is no part of its surface.
    let mut flying = first.clone();
    flying.push(Grain { id: 9_999, z: plan.passes[0].tip + 50.0 * d, ..first[first.len() / 2] });
    let again = passes(&sc, &plan, &lines, &[], &[flying, both]);
    assert_eq!(again[1].effective_thickness_m, recs[1].effective_thickness_m);
}

#[test]
fn the_log_gives_each_pass_its_plate_mass() {
    let log = "step atoms\ndemsweep: layer 1 step 1200 plate 3.5e-07 count 420\nnoise\n\
               demsweep: layer 2 step 2400 plate 7.25e-07 count 860\ndemsweep: layers done at step 2400\n";
    let lines = parse_log(log);
    assert_eq!(lines.len(), 2);
    assert_eq!(lines[1], PassLine { k: 2, step: 2400, plate_mass: 7.25e-7 });
}

#[test]
fn a_roller_s_load_is_read_per_metre_of_its_width_and_a_torn_line_is_not() {
    let log = "demsweep: roller 1 torque 2e-05 turning 0.004 push 0.01 pushing 0.001\n\
               demsweep: roller 2 torque 4e-05 turning 0.008\n";
    let loads = super::measure::parse_roller(log, 0.002);
    assert_eq!(loads.len(), 1);
    let (k, l) = loads[0];
    assert_eq!(k, 1);
    for (got, want) in [
        (l.torque_nm_per_m, 0.01),
        (l.turning_power_w_per_m, 2.0),
        (l.push_n_per_m, 5.0),
        (l.pushing_power_w_per_m, 0.5),
    ] {
        assert!((got - want).abs() < 1e-12 * want, "{got} against {want}");
    }
}

#[test]
fn the_powder_sent_over_a_roller_is_read_per_metre_and_an_old_result_reads_without_it() {
    let log = "demsweep: ejected 1 mass 3e-09 count 12\ndemsweep: ejected 2 mass\ndemsweep: ejected 3 mass 0 count 0\n";
    assert_eq!(super::measure::parse_ejected(log, 0.002), vec![(1, 1.5e-6), (3, 0.0)]);
    let old = r#"{"torque_nm_per_m": 1e-6, "turning_power_w_per_m": 1e-4, "push_n_per_m": 1e-3, "pushing_power_w_per_m": 1e-4}"#;
    let load: crate::scenes::layers::result::RollerLoad = serde_json::from_str(old).unwrap();
    assert_eq!(load.ejected_kg_per_m, None);
    assert!(!serde_json::to_string(&load).unwrap().contains("ejected"));
}

#[test]
fn the_held_bed_a_pass_removes_is_counted_on_the_plate_of_every_later_pass() {
    let log = "demsweep: layer 1 step 100 plate 1.0e-06 count 10\n\
               demsweep: buried 1 mass 2.5e-07 count 3\n\
               demsweep: layer 2 step 200 plate 1.5e-06 count 14\n\
               demsweep: buried 2 mass 1.0e-07 count 1\n\
               demsweep: layer 3 step 300 plate 1.75e-06 count 18\n";
    let mass: Vec<f64> = parse_log(log).iter().map(|l| l.plate_mass).collect();
    assert_eq!(mass, [1.0e-6, 1.5e-6 + 2.5e-7, 1.75e-6 + 2.5e-7 + 1.0e-7]);
}

fn record(k: usize, y: f64) -> crate::scenes::layers::result::PassRecord {
    crate::scenes::layers::result::PassRecord {
        search: false,
        k,
        deposit_m: y * 1e-4,
        relative_density: y,
        effective_thickness_m: 1e-4,
        packing: y,
        covered_fraction: 1.0,
        roughness_d: 0.3,
        bed_relative_density: None,
        particles: 100,
        roller: None,
    }
}

#[test]
fn the_steady_layer_starts_after_the_first_layers_transient() {
    let plan = plan_of(&scene(&settings()));
    // A first layer well below the bed's, then scatter about 0.60.
    let y = [0.45, 0.55, 0.605, 0.598, 0.601, 0.603, 0.597, 0.600, 0.602, 0.599];
    let s = steady_layer(&plan, y.iter().enumerate().map(|(i, &v)| record(i + 1, v)).collect());
    assert!(s.steady_from >= 3, "steady from {}", s.steady_from);
    assert!(s.steady);
    assert!((s.relative_density - 0.6).abs() < 0.003);
    assert!(s.relative_density_se > 0.0 && s.relative_density_se < 0.003);
    // A bed still filling up by the last pass is not steady.
    let rising: Vec<_> =
        (0..10).map(|i| record(i + 1, 0.5 + 0.01 * i as f64 + 0.001 * (i % 2) as f64)).collect();
    assert!(!steady_layer(&plan, rising).steady);
}

#[test]
fn the_round_blade_is_an_arc_whose_lowest_line_is_the_tip() {
    let s = with_own(settings(), |l| {
        l.blade_profile = "round".into();
        l.blade_radius_mm = 1.0;
    });
    let sc = scene(&s);
    let plan = plan_of(&sc);
    let stl = Layers.mesh(&sc);
    let mut lowest = (f64::INFINITY, 0.0);
    let mut n_facets = 0;
    let mut verts: Vec<[f64; 3]> = Vec::new();
    let mut normal = [0.0; 3];
    for line in stl.lines().map(str::trim) {
        let nums = |t: &str| -> Vec<f64> { t.split_whitespace().map(|v| v.parse().unwrap()).collect() };
        if let Some(rest) = line.strip_prefix("facet normal") {
            let v = nums(rest);
            normal = [v[0], v[1], v[2]];
        } else if let Some(rest) = line.strip_prefix("vertex") {
            let v = nums(rest);
            if v[2] < lowest.0 {
                lowest = (v[2], v[0]);
            }
            verts.push([v[0], v[1], v[2]]);
            if verts.len() == 3 {
                let (a, b, c) = (verts[0], verts[1], verts[2]);
                let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
                let w = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
                let cross = [u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]];
                let dot: f64 = (0..3).map(|i| cross[i] * normal[i]).sum();
                assert!(dot > 0.0, "winding disagrees with normal {normal:?}");
                // Outward: away from the cylinder's axis or up through the lid.
                let centre = [(a[0] + b[0] + c[0]) / 3.0, (a[2] + b[2] + c[2]) / 3.0];
                let out = (centre[0] - plan.tip_x0) * normal[0] + (centre[1] - plan.blade_radius) * normal[2];
                assert!(out > 0.0 || normal[2] > 0.99, "inward facet at {centre:?}");
                verts.clear();
                n_facets += 1;
            }
        }
    }
    assert!(n_facets > 90);
    assert!(lowest.0.abs() < 1e-12, "lowest z {}", lowest.0);
    assert!((lowest.1 - plan.tip_x0).abs() < 1e-9);
    // The extra meshes: the feed platform, the wall after the plate, the plate, the pit's wall.
    let names: Vec<&str> = Layers.extra_meshes(&sc).iter().map(|(n, _)| *n).collect();
    assert_eq!(names, ["feed.stl", "wall.stl", "plate.stl", "pit.stl"]);
}

#[test]
fn a_fused_bed_s_search_sets_each_next_depth_to_its_own_times_the_drop_over_its_deposit() {
    let s = with_own(settings(), |l| {
        l.bed = "fused".into();
        l.layers = 6;
        l.search_passes = Some(2);
    });
    let sc = scene(&s);
    let plan = plan_of(&sc);
    assert_eq!(plan.search_passes, 2);
    // The faces below the top reach past the deepest solid a search may set.
    assert!(plan.block_depth >= plan.passes[5].top + plan.search_max_depth);
    let mut tera = tera::Tera::default();
    tera.add_raw_template("layers", TEMPLATE.source).unwrap();
    let mut context = tera::Context::new();
    context.insert("scene", &sc);
    let deck = tera.render("layers", &context).unwrap();
    // LIGGGHTS evaluates the rule: pass 1 met the drop and the clearance (1.5e-4 m) under its
    // tip; the next solid is set below pass 2's tip (2.5e-4 m) by that depth times the drop over
    // pass 1's deposit, and pass 2's depth is measured from that solid.
    let line = |name: &str| {
        let head = format!("variable {name} equal ");
        deck.lines().find_map(|l| l.strip_prefix(head.as_str())).unwrap_or_else(|| panic!("{name}: {deck}"))
    };
    let number_before = |expr: &str, rest: &str| -> f64 { expr.strip_suffix(rest).unwrap().parse().unwrap() };
    assert!((number_before(line("depth1"), "-0.0") - 1.5e-4).abs() < 1e-15);
    assert!((number_before(line("solid1"), "-${kept1}") - 2.5e-4).abs() < 1e-15);
    assert_eq!(line("asked1"), "${depth1}*0.0001/${counted1}");
    assert!(line("depth2").ends_with("-${solid1}"), "{}", line("depth2"));
    // Pass 3 is the first laid on the one before: its solid is the last plus its deposit.
    assert!(deck.contains("variable solid3 equal ${solid2}+${platemass}"), "{deck}");
    assert!(!deck.contains("variable depth3 "));

    // Measured: the floor under each pass is the solid the log printed, and the search passes
    // are never the steady layer.
    let d = sc.diameter;
    let layer = lattice(&sc, &plan, d, 0.5 * d, 1);
    let m = sc.material.density * std::f64::consts::PI / 6.0 * d.powi(3) * layer.len() as f64;
    let lines: Vec<PassLine> = (1..=6).map(|k| PassLine { k, step: 10 * k as u64, plate_mass: m }).collect();
    let log = "demsweep: solid 1 top -0.00025\ndemsweep: solid 2 top -0.0001\n";
    let solids = parse_solids(log);
    assert_eq!(solids, [(1, -2.5e-4), (2, -1e-4)]);
    let grains: Vec<Vec<Grain>> =
        (0..6).map(|k| lattice(&sc, &plan, d, 0.5 * d, 1 + 10_000 * k as u64)).collect();
    let recs = passes(&sc, &plan, &lines, &solids, &grains);
    // The deck renumbers every ID left after a fused pass (delete_atoms compresses them): the
    // same IDs in every pass's dump are each pass's own particles all the same.
    let same_ids: Vec<Vec<Grain>> = (0..6).map(|_| layer.clone()).collect();
    let renumbered = passes(&sc, &plan, &lines, &solids, &same_ids);
    for (a, b) in recs.iter().zip(&renumbered) {
        assert_eq!((a.particles, a.covered_fraction), (b.particles, b.covered_fraction), "pass {}", a.k);
    }
    assert_eq!(renumbered[3].particles, layer.len());
    assert!((recs[1].effective_thickness_m - (plan.passes[1].tip + 2.5e-4)).abs() < 1e-15);
    assert!((recs[2].effective_thickness_m - (plan.passes[2].tip + 1e-4)).abs() < 1e-15);
    // After the search the solid rises by the deposit.
    let deposit = recs[2].deposit_m;
    assert!((recs[3].effective_thickness_m - (plan.passes[3].tip + 1e-4 - deposit)).abs() < 1e-15);
    assert_eq!(recs.iter().filter(|r| r.search).count(), 2);
    let series = steady_layer(&plan, recs);
    assert!(series.steady_from >= 3, "steady from {}", series.steady_from);
}

#[test]
fn a_fused_bed_whose_depth_still_grows_is_not_steady_though_its_packing_is() {
    let plan = plan_of(&scene(&with_own(settings(), |l| {
        l.bed = "fused".into();
        l.layers = 8;
        l.search_passes = Some(0);
    })));
    // The packing settles at 0.225 by pass 4 while the depth still creeps toward the drop over
    // it (as Ti-6Al-4V on a round blade did, docs/study/layers.md).
    let packing = [0.39, 0.33, 0.29, 0.226, 0.224, 0.227, 0.225, 0.226];
    let depth: [f64; 8] = [50.0, 128.0, 152.0, 194.0, 203.0, 207.0, 211.0, 214.0];
    let passes = |grow: bool| {
        (0..8)
            .map(|i| crate::scenes::layers::result::PassRecord {
                effective_thickness_m: if grow { depth[i] } else { depth[i].min(203.0) } * 1e-6,
                // Each pass keeps the drop: the bed keeps pace, only its depth trends.
                relative_density: 1.0,
                ..record(i + 1, packing[i])
            })
            .collect::<Vec<_>>()
    };
    let growing = steady_layer(&plan, passes(true));
    assert!(!growing.steady);
    assert!(steady_layer(&plan, passes(false)).steady);
    // The reason names the series that trends: the depth, not the settled packing.
    let why = super::measure::unsteady_why(&plan, &growing);
    assert!(why.starts_with("its depth under the blade trends over passes"), "{why}");
}

#[test]
fn a_fused_bed_that_leaves_less_than_the_drop_is_said_to_fall_behind() {
    let plan = plan_of(&scene(&with_own(settings(), |l| {
        l.bed = "fused".into();
        l.layers = 8;
        l.search_passes = Some(0);
    })));
    // Each pass leaves 0.65 of the drop (the round blade at 0.2 m/s at 50 µm), the depth growing.
    let passes: Vec<_> = (0..8)
        .map(|i| crate::scenes::layers::result::PassRecord {
            relative_density: 0.645 + 0.01 * (i % 2) as f64,
            effective_thickness_m: (1000.0 + 17.0 * i as f64) * 1e-6,
            ..record(i + 1, 0.03)
        })
        .collect();
    let series = steady_layer(&plan, passes);
    assert!(!series.steady);
    let why = super::measure::unsteady_why(&plan, &series);
    assert!(
        why.starts_with("the bed falls behind") && why.contains("0.65") && why.contains("supply_factor"),
        "{why}"
    );
    // A loose bed's relative density is its packing, not a share it must keep.
    let loose = plan_of(&scene(&settings()));
    assert!(!super::measure::unsteady_why(&loose, &series).contains("falls behind"));
}

#[test]
fn a_fused_bed_searches_by_default_as_far_as_its_passes_allow_and_a_loose_one_never() {
    let fused = |layers: usize| {
        with_own(settings(), |l| {
            l.bed = "fused".into();
            l.layers = layers;
        })
    };
    assert_eq!(search_passes(&fused(24)), DEFAULT_SEARCH_PASSES);
    assert_eq!(search_passes(&fused(14)), DEFAULT_SEARCH_PASSES);
    // Six laid passes are left after a default search: three for the steady layer and three
    // for MSER to cut.
    assert_eq!(search_passes(&fused(10)), 4);
    assert_eq!(search_passes(&fused(7)), 1);
    assert_eq!(search_passes(&fused(6)), 0);
    assert_eq!(search_passes(&with_own(fused(24), |l| l.search_passes = Some(0))), 0);
    assert_eq!(search_passes(&with_own(settings(), |l| l.layers = 24)), 0);
    assert!(Layers.check_settings(&fused(2)).is_ok());
}

#[test]
fn a_fused_bed_s_dose_is_twice_a_loose_one_s_and_supply_factor_scales_both() {
    let dose = |bed: &str, supply: f64| {
        let s = with_own(SceneSettings { supply_factor: supply, ..settings() }, |l| l.bed = bed.into());
        plan_of(&scene(&s)).dose_particles as f64
    };
    // A steady fused pass must leave a whole drop of solid, a loose one about 0.6 of it.
    let (loose, fused) = (dose("loose", 1.0), dose("fused", 1.0));
    assert!((fused / loose - 2.0).abs() < 0.02, "fused {fused} against loose {loose}");
    // The loose dose holds DOSE_FACTOR layers at LAYER_FRACTION_MAX (mono spheres of 65 µm).
    let sc = scene(&settings());
    let layer = (20.0 * sc.diameter) * 1e-4 * LAYER_FRACTION_MAX * sc.depth;
    let sphere = std::f64::consts::PI / 6.0 * sc.diameter.powi(3);
    assert!((loose - DOSE_FACTOR * layer / sphere).abs() <= 1.0, "{loose}");
    assert!((dose("fused", 0.5) / fused - 0.5).abs() < 0.02);
}

#[test]
fn a_trendless_layer_is_called_unsteady_at_the_rule_s_stated_rate() {
    use rand::SeedableRng;
    use rand_distr::{Distribution, StandardNormal};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(44);
    let mut noise = |n: usize| -> Vec<f64> { (0..n).map(|_| StandardNormal.sample(&mut rng)).collect() };
    // The slope test alone, at the lengths a steady layer keeps: its level, one series or two.
    let trials = 20_000;
    for n in [4, 5, 8, 12] {
        for series in [1, 2] {
            let limit = super::measure::trend_limit(n, series, 0.0);
            let alarms =
                (0..trials).filter(|_| crate::measure::steady::trend_z(&noise(n)).abs() > limit).count();
            let rate = alarms as f64 / trials as f64;
            let want = TREND_FALSE_ALARM / series as f64;
            // Binomial SD at 20,000 trials is 0.0015 at 5 %.
            assert!((rate - want).abs() < 0.006, "{n} passes, {series} series: {rate} against {want}");
        }
    }
    // The slope test of correlated passes, at the lag-1 autocorrelation a fused bed's depth has:
    // its level holds where, read as independent, 14 % of eight passes would trend.
    let mut ar1 = |n: usize, rho: f64| -> Vec<f64> {
        let e: f64 = StandardNormal.sample(&mut rng);
        let mut x = e / (1.0 - rho * rho).sqrt();
        (0..n)
            .map(|_| {
                x = rho * x + {
                    let e: f64 = StandardNormal.sample(&mut rng);
                    e
                };
                x
            })
            .collect()
    };
    for n in [4, 8, 12] {
        let limit = super::measure::trend_limit(n, 1, FUSED_DEPTH_LAG1);
        let alarms = (0..trials)
            .filter(|_| crate::measure::steady::trend_z(&ar1(n, FUSED_DEPTH_LAG1)).abs() > limit)
            .count();
        let rate = alarms as f64 / trials as f64;
        assert!((rate - TREND_FALSE_ALARM).abs() < 0.01, "{n} correlated passes: {rate}");
    }
    // The whole rule on a fused bed of 14 passes (6 searched) with no trend in either series,
    // each as correlated as the rule allows for: MSER's cut and two tests together (2.6 % here).
    let plan = plan_of(&scene(&with_own(settings(), |l| {
        l.bed = "fused".into();
        l.layers = 14;
        l.search_passes = Some(6);
    })));
    let points = 4_000;
    let unsteady = (0..points)
        .filter(|_| {
            let (p, d) = (ar1(14, FUSED_PACKING_LAG1), ar1(14, FUSED_DEPTH_LAG1));
            let recs = (0..14)
                .map(|i| crate::scenes::layers::result::PassRecord {
                    search: i < 6,
                    effective_thickness_m: (130.0 + 0.4 * d[i]) * 1e-6,
                    ..record(i + 1, 0.37 + 0.004 * p[i])
                })
                .collect();
            !steady_layer(&plan, recs).steady
        })
        .count();
    let rate = unsteady as f64 / points as f64;
    assert!(rate < 0.06, "{rate} of trendless fused beds called unsteady");
}

#[test]
fn a_loose_bed_is_held_still_below_its_freeze_depth_from_the_first_pass_whose_top_is_that_deep() {
    // Refused where it cannot mean anything: a fused bed, a depth inside the blade's reach.
    let fused = with_own(settings(), |l| {
        l.bed = "fused".into();
        l.freeze_depth_diameters = 10.0;
    });
    assert_eq!(Layers.check_settings(&fused).unwrap_err().key, "scene.freeze_depth_diameters");
    for bad in [1.0, -1.0, f64::NAN, 1e9] {
        let s = with_own(settings(), |l| l.freeze_depth_diameters = bad);
        let err = Layers.check_settings(&s).unwrap_err();
        assert_eq!(err.key, "scene.freeze_depth_diameters", "{bad}");
        assert!(!err.why.contains('\n'));
    }
    let s = with_own(settings(), |l| {
        l.layers = 8;
        l.freeze_depth_diameters = 3.0;
    });
    assert!(Layers.check_settings(&s).is_ok());
    let sc = scene(&s);
    let plan = plan_of(&sc);
    assert!((plan.freeze_depth - 3.0 * sc.diameter).abs() < 1e-18);
    let mut tera = tera::Tera::default();
    tera.add_raw_template("layers", TEMPLATE.source).unwrap();
    let mut context = tera::Context::new();
    context.insert("scene", &sc);
    let deck = tera.render("layers", &context).unwrap();
    // A pass holds still what lies below its top minus the depth, once that is above the plate;
    // the plate is then measured over every particle, held still or not.
    for p in &plan.passes[..8] {
        let cut = p.top - plan.freeze_depth;
        let line = format!("region deep{} block", p.k);
        match deck.lines().find(|l| l.starts_with(&line)) {
            Some(l) => {
                assert!(cut > 0.0, "pass {}: {l}", p.k);
                let z: f64 = l.split_whitespace().nth(8).unwrap().parse().unwrap();
                assert!((z - cut).abs() < 1e-15, "{l}");
            }
            None => assert!(cut <= 0.0, "pass {} holds nothing still", p.k),
        }
    }
    // And removes what lies a held skin of two largest diameters deeper, once that is above the
    // plate, at the pass's end.
    let skin = super::plan::BURY_SKIN_DIAMETERS * plan.max_diameter();
    assert!((plan.bury_depth - plan.freeze_depth - skin).abs() < 1e-15);
    let mut buried = 0;
    for p in &plan.passes[..8] {
        let cut = p.top - plan.bury_depth;
        let line = format!("region buried{} block", p.k);
        match deck.lines().find(|l| l.starts_with(&line)) {
            Some(l) => {
                let z: f64 = l.split_whitespace().nth(8).unwrap().parse().unwrap();
                assert!(cut > 0.0 && (z - cut).abs() < 1e-15, "{l}");
                buried += 1;
            }
            None => assert!(cut <= 0.0, "pass {} removes nothing", p.k),
        }
    }
    assert!(buried > 0, "eight passes of 3 D holding 3 D deep remove the bed below");
    assert!(deck.contains("group powder subtract powder frozen"));
    assert!(deck.contains("variable platemass equal mass(all,plate)"));
    assert!(deck.contains("dump layer8 all custom"));
    // Off (the default), the deck measures the powder as before.
    let off = tera.render("layers", &{
        let mut c = tera::Context::new();
        c.insert("scene", &scene(&with_own(settings(), |l| l.layers = 8)));
        c
    });
    let off = off.unwrap();
    assert!(!off.contains("frozen") && off.contains("mass(powder,plate)"));
}

#[test]
fn the_roller_is_a_whole_circle_about_its_axis_turning_at_minus_its_ratio_over_its_radius() {
    let s = with_own(settings(), |l| {
        l.blade_profile = "roller".into();
        l.blade_radius_mm = 1.0;
    });
    let mut v =
        values(&[("diameter", 0.065), ("layer_thickness", 0.1), ("blade_speed", 0.1), ("density", 4386.0)]);
    v.insert("roller_speed_ratio".into(), 3.0);
    let sc = crate::scenes::build(&v, &s).unwrap();
    let plan = plan_of(&sc);
    assert!(plan.roller);
    assert_eq!(plan.roller_speed_ratio, 3.0);
    // ω about +y per unit travel speed: counter-rotating, the lowest line runs ahead (ω < 0).
    assert!((plan.roller_spin + 3.0 / 1e-3).abs() < 1e-9, "{}", plan.roller_spin);
    // It is taken away only once all of it is past the plate (what it carries falls in the
    // pit), and it stays inside the box.
    let r = plan.blade_radius;
    assert!(plan.tip_x0 + plan.travel - r > plan.plate_x1, "the roller is taken away over the plate");
    assert!(plan.tip_x0 + plan.travel + r < sc.x_hi, "the roller leaves the box");
    // Every vertex on the circle of radius r about (tip_x0, r), all the way round; the corners
    // of scene.roller_segments' polygon (128 by default).
    let corners = |sc: &Scene| {
        let stl = Layers.mesh(sc);
        let v: std::collections::HashSet<String> = stl
            .lines()
            .filter_map(|l| l.trim().strip_prefix("vertex"))
            .map(|l| l.split_whitespace().step_by(2).collect())
            .collect();
        v.len()
    };
    let fine = crate::scenes::build(&v, &with_own(s.clone(), |l| l.roller_segments = 256)).unwrap();
    assert_eq!((corners(&sc), corners(&fine)), (128, 256));
    let angles: Vec<f64> = Layers
        .mesh(&sc)
        .lines()
        .filter_map(|l| l.trim().strip_prefix("vertex"))
        .map(|l| {
            let p: Vec<f64> = l.split_whitespace().map(|x| x.parse().unwrap()).collect();
            let (x, z) = (p[0] - plan.tip_x0, p[2] - r);
            assert!(((x * x + z * z).sqrt() - r).abs() < 1e-9 * r, "vertex {p:?} off the circle");
            z.atan2(x)
        })
        .collect();
    let n = super::settings::DEFAULT_ROLLER_SEGMENTS;
    let step = 2.0 * std::f64::consts::PI / n as f64;
    for k in 0..n {
        let a = -std::f64::consts::PI + k as f64 * step;
        assert!(angles.iter().any(|b| (b - a)
            .rem_euclid(2.0 * std::f64::consts::PI)
            .min((a - b).rem_euclid(2.0 * std::f64::consts::PI))
            < 1e-9));
    }
    // The deck turns it; a roller that does not turn (ratio 0) and a round blade are not turned.
    let render = |sc: &Scene| {
        let mut tera = tera::Tera::default();
        tera.add_raw_template("layers", TEMPLATE.source).unwrap();
        let mut context = tera::Context::new();
        context.insert("scene", sc);
        tera.render("layers", &context).unwrap()
    };
    assert_eq!(render(&sc).matches("rotate/variable").count(), own(&s).layers);
    v.insert("roller_speed_ratio".into(), 0.0);
    assert!(!render(&crate::scenes::build(&v, &s).unwrap()).contains("rotate/variable"));
    let round = with_own(s.clone(), |l| l.blade_profile = "round".into());
    assert!(crate::scenes::build(&v, &round).is_ok());
    v.insert("roller_speed_ratio".into(), 1.0);
    let err = crate::scenes::build(&v, &round).unwrap_err().to_string();
    assert!(err.contains("roller_speed_ratio") && err.contains("turns no roller"), "{err}");
}
