// Scenes without alpha masks: every triangle is opaque, and no mask code or buffers exist.

fn is_opaque(leaf: u32, u: f32, v: f32) -> bool {
    return true;
}
