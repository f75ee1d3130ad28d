//! `vcm merge`: put the shards of one image together (`vcm render --samples A..B --state`).

use std::path::PathBuf;

use anyhow::bail;
use vcm_rs::state::RenderState;

use crate::render::{check_outputs, png_beside};

/// Arguments of `vcm merge`.
#[derive(clap::Args)]
pub struct MergeArgs {
    /// The render states to merge: the same scene and settings, disjoint samples.
    #[arg(required = true, num_args = 1..)]
    states: Vec<PathBuf>,
    /// Output EXR (linear radiance); a tone-mapped PNG is written beside it.
    #[arg(short, long, default_value = "out.exr")]
    output: PathBuf,
    /// Also write the merged state to this file (to resume or merge further).
    #[arg(long, value_name = "FILE")]
    state: Option<PathBuf>,
}

/// Merges the states, refusing mismatched or overlapping ones, and writes the image (and
/// the merged state).
pub fn run(args: &MergeArgs) -> anyhow::Result<()> {
    let mut outputs = vec![
        ("the EXR image", args.output.clone()),
        ("the tone-mapped PNG", png_beside(&args.output)),
    ];
    outputs.extend(args.state.clone().map(|state| ("the merged state", state)));
    let inputs: Vec<_> = args.states.iter().map(PathBuf::as_path).collect();
    check_outputs(&outputs, &inputs)?;
    let Some((first, rest)) = args.states.split_first() else {
        bail!("name at least one render state to merge");
    };
    let mut merged = RenderState::load(first)?;
    for path in rest {
        let state = RenderState::load(path)?;
        let (ours, theirs) = (first.display().to_string(), path.display().to_string());
        merged.merge(&state, &ours, &theirs)?;
    }
    if merged.samples.is_empty() {
        bail!("the states hold no samples: there is no image to write");
    }
    let image = merged.image();
    image.write_exr(&args.output)?;
    let png = png_beside(&args.output);
    image.write_png(&png, 0.0)?;
    say!(
        "merged {} states: samples {} ({} per pixel)",
        args.states.len(),
        merged.samples,
        merged.samples.count()
    );
    if let Some(path) = &args.state {
        merged.output = Some(args.output.clone());
        merged.save(path)?;
        say!("wrote the render state {}", path.display());
    }
    say!("wrote {} and {}", args.output.display(), png.display());
    Ok(())
}
