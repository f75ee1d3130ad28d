//! vcm-rs's CPU traversal against Embree 4 on the same triangles and the same rays: the
//! traversal benchmark's ~1M-triangle scene and Cornell box, with coherent primary rays
//! (one per pixel, row by row), incoherent diffuse-bounce rays and shadow rays.
//!
//! Run with `cargo bench --bench embree` after `pip install embreex` (the Python running it:
//! `VCM_PYTHON`, else `python3`). Each scene's rays and triangles are written to a temporary
//! folder; `tools/embree_traversal.py` traces them through Embree's single-ray API on as many
//! threads as rayon has here. The two are timed in turns (vcm-rs, Embree, Embree, vcm-rs, …,
//! `VCM_EMBREE_ROUNDS` rounds, 4 by default), each turn the median of five passes over the
//! set; the table gives the medians of the turns with their ranges, and how many rays agree
//! (the same triangle, or a hit at the same distance: a tie on a shared edge). The binding
//! loops over the rays in Cython, which costs time per ray that a renderer calling Embree
//! from C would not pay; the script measures it on rays that miss the scene's bounds, and
//! the column Embree* gives Embree's rates with it taken out. Without embreex only vcm-rs's
//! rates are printed.

mod common;

use std::fs;
use std::io::{self, Write};
use std::path::Path;
use std::process::Command;
use std::time::Instant;

use common::{Scene, Workload, cornell_box, million_triangles};
use vcm_traversal::{CpuBvh, CpuBvhOptions, HitBatch, RayBatch, Traversal};

/// Timed passes over a ray set per turn; the turn's time is their median.
const PASSES: usize = 5;

/// Relative difference of two hit distances counted as the same hit (a shared edge's tie).
const SAME_DISTANCE: f32 = 1e-5;

/// What a ray set asks of the traversal.
#[derive(Clone, Copy, PartialEq)]
enum Query {
    Closest,
    Occluded,
}

impl Query {
    fn name(self) -> &'static str {
        match self {
            Self::Closest => "closest",
            Self::Occluded => "occluded",
        }
    }
}

/// One ray set and what both sides measured on it.
struct RaySet<'a> {
    name: &'static str,
    rays: &'a RayBatch,
    query: Query,
    /// Seconds per pass, one median per turn.
    vcm: Vec<f64>,
    embree: Vec<f64>,
    /// Embree's times less the binding's per-ray loop.
    embree_own: Vec<f64>,
}

/// The median of `values` (sorted in place).
fn median(values: &mut [f64]) -> f64 {
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

/// Median and range of the M rays/s that `seconds` (one per turn) give for `rays` rays.
fn rates(rays: usize, seconds: &[f64]) -> (f64, f64, f64) {
    let mut rates: Vec<f64> = seconds.iter().map(|s| rays as f64 / s / 1e6).collect();
    let middle = median(&mut rates);
    (middle, rates[0], rates[rates.len() - 1])
}

fn write_floats(path: &Path, values: impl Iterator<Item = f32>) -> io::Result<()> {
    let mut file = io::BufWriter::new(fs::File::create(path)?);
    for value in values {
        file.write_all(&value.to_le_bytes())?;
    }
    file.flush()
}

fn read_floats(path: &Path) -> io::Result<Vec<f32>> {
    let bytes = fs::read(path)?;
    Ok(bytes
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect())
}

/// Writes the folder `tools/embree_traversal.py` reads.
fn write_inputs(folder: &Path, scene: &Scene, sets: &[RaySet]) -> io::Result<()> {
    let corners = scene.triangles.iter().flatten().flat_map(|p| p.to_array());
    write_floats(&folder.join("triangles.f32"), corners)?;
    let mut list = String::new();
    for set in sets {
        list += &format!("{} {}\n", set.name, set.query.name());
        let rays = set.rays;
        let ray = |i: usize| {
            let (o, d) = (rays.origin(i), rays.direction(i));
            [o.x, o.y, o.z, d.x, d.y, d.z, rays.tmin[i], rays.tmax[i]]
        };
        write_floats(
            &folder.join(format!("{}.rays.f32", set.name)),
            (0..rays.len()).flat_map(ray),
        )?;
    }
    fs::write(folder.join("sets.txt"), list)
}

/// Rays in the script's pass that measures the binding's per-ray cost.
const OVERHEAD_RAYS: f64 = 1e6;

/// One turn of Embree over every set: appends each set's median pass time, and returns the
/// median time of a pass of [`OVERHEAD_RAYS`] rays that cost Embree nothing (the binding's
/// per-ray loop alone). `Err` with the reason when Embree cannot run here.
fn embree_turn(folder: &Path, sets: &mut [RaySet]) -> Result<f64, String> {
    let python = std::env::var("VCM_PYTHON").unwrap_or_else(|_| "python3".into());
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/tools/embree_traversal.py");
    let output = Command::new(&python)
        .arg(script)
        .arg(folder)
        .args(["--threads", &rayon::current_num_threads().to_string()])
        .args(["--repeats", &PASSES.to_string()])
        .output()
        .map_err(|e| format!("cannot run {python}: {e}"))?;
    if !output.status.success() {
        return Err(String::from_utf8_lossy(&output.stderr).trim().to_owned());
    }
    let stdout = String::from_utf8_lossy(&output.stdout);
    let mut overhead = None;
    for line in stdout.lines() {
        let mut fields = line.split_whitespace();
        let name = fields.next().unwrap_or_default();
        let mut seconds: Vec<f64> = fields.filter_map(|s| s.parse().ok()).collect();
        if seconds.is_empty() {
            return Err(format!("unexpected line from the script: {line}"));
        }
        let time = median(&mut seconds);
        match sets.iter_mut().find(|s| s.name == name) {
            Some(set) => set.embree.push(time),
            None if name == "overhead" => overhead = Some(time),
            None => return Err(format!("unexpected line from the script: {line}")),
        }
    }
    overhead.ok_or_else(|| "the script printed no overhead line".into())
}

/// One turn of vcm-rs over every set: appends each set's median pass time.
fn vcm_turn(bvh: &CpuBvh, sets: &mut [RaySet]) {
    let mut hits = HitBatch::default();
    let mut occluded = Vec::new();
    for set in sets {
        let mut seconds: Vec<f64> = (0..PASSES)
            .map(|_| {
                let start = Instant::now();
                match set.query {
                    Query::Closest => bvh.intersect(set.rays, &mut hits),
                    Query::Occluded => bvh.occluded(set.rays, &mut occluded),
                }
                start.elapsed().as_secs_f64()
            })
            .collect();
        set.vcm.push(median(&mut seconds));
    }
}

/// How many of the set's rays vcm-rs and Embree answer alike (Embree's answers as
/// `tools/embree_traversal.py` wrote them).
fn agreeing(bvh: &CpuBvh, folder: &Path, set: &RaySet) -> io::Result<usize> {
    let embree = read_floats(&folder.join(format!("{}.embree.f32", set.name)))?;
    let rays = set.rays;
    Ok(match set.query {
        Query::Closest => {
            let mut hits = HitBatch::default();
            bvh.intersect(rays, &mut hits);
            (0..rays.len())
                .filter(|&i| {
                    let (t, prim) = (embree[2 * i], embree[2 * i + 1]);
                    match (hits.is_hit(i), prim >= 0.0) {
                        (false, false) => true,
                        (true, true) => {
                            hits.prim[i] as f32 == prim
                                || (hits.t[i] - t).abs() <= SAME_DISTANCE * t.abs().max(1.0)
                        }
                        _ => false,
                    }
                })
                .count()
        }
        Query::Occluded => {
            let mut occluded = Vec::new();
            bvh.occluded(rays, &mut occluded);
            (0..rays.len())
                .filter(|&i| occluded[i] == (embree[2 * i] == 1.0))
                .count()
        }
    })
}

fn compare(scene: &Scene, rounds: usize) -> io::Result<()> {
    let bvh = CpuBvh::new(&scene.triangles, CpuBvhOptions::default()).expect("valid scene");
    let workload = Workload::new(scene, &bvh);
    let set = |name, rays, query| RaySet {
        name,
        rays,
        query,
        vcm: Vec::new(),
        embree: Vec::new(),
        embree_own: Vec::new(),
    };
    let mut sets = [
        set("primary", &workload.primary, Query::Closest),
        set("bounce", &workload.bounce, Query::Closest),
        set("shadow", &workload.shadow, Query::Occluded),
    ];
    let folder = tempfile::tempdir()?;
    write_inputs(folder.path(), scene, &sets)?;
    let mut embree_missing = None;
    let mut overheads = Vec::new();
    for round in 0..rounds {
        // Turns in the order A B B A A B …, so that drifts of the machine's speed cancel.
        if round % 2 == 0 {
            vcm_turn(&bvh, &mut sets);
        }
        if embree_missing.is_none() {
            match embree_turn(folder.path(), &mut sets) {
                Ok(overhead) => overheads.push(overhead),
                Err(reason) => embree_missing = Some(reason),
            }
        }
        if round % 2 == 1 {
            vcm_turn(&bvh, &mut sets);
        }
    }
    println!(
        "{}: {} triangles, {} threads, {rounds} turns each",
        scene.name,
        scene.triangles.len(),
        rayon::current_num_threads()
    );
    if let Some(reason) = &embree_missing {
        println!("  Embree not run: {reason}");
    } else {
        let overhead = median(&mut overheads) / OVERHEAD_RAYS;
        println!(
            "  the binding's per-ray loop: {:.0} ns per ray and thread (Embree* leaves it out)",
            overhead * 1e9 * rayon::current_num_threads() as f64
        );
        // Embree's own time per pass: the binding's share taken out.
        for set in &mut sets {
            let own = overhead * set.rays.len() as f64;
            set.embree_own = set.embree.iter().map(|t| t - own).collect();
        }
    }
    let mut header = String::from("  set      rays     vcm-rs M rays/s");
    if embree_missing.is_none() {
        header += "      Embree M rays/s      Embree* M rays/s     vcm-rs/Embree  \
                   vcm-rs/Embree*  agreeing";
    }
    println!("{header}");
    for set in &sets {
        let (vcm, vcm_low, vcm_high) = rates(set.rays.len(), &set.vcm);
        let mut line = format!(
            "  {:<8} {:>7}  {vcm:6.2} ({vcm_low:.2}–{vcm_high:.2})",
            set.name,
            set.rays.len()
        );
        if embree_missing.is_none() {
            let (embree, low, high) = rates(set.rays.len(), &set.embree);
            let (own, own_low, own_high) = rates(set.rays.len(), &set.embree_own);
            let agree = agreeing(&bvh, folder.path(), set)?;
            line += &format!(
                "  {embree:6.2} ({low:.2}–{high:.2})  {own:6.2} ({own_low:.2}–{own_high:.2})  \
                 {:6.2}         {:6.2}          {agree}/{}",
                vcm / embree,
                vcm / own,
                set.rays.len()
            );
        }
        println!("{line}");
    }
    Ok(())
}

fn main() -> io::Result<()> {
    let rounds = std::env::var("VCM_EMBREE_ROUNDS")
        .ok()
        .and_then(|r| r.parse().ok())
        .unwrap_or(4);
    compare(&million_triangles(), rounds)?;
    compare(&cornell_box(), rounds)
}
