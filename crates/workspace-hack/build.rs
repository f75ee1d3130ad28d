// A build script, so that Cargo applies this crate's build-dependencies (the features of
// the crates that build scripts and procedural macros use).
fn main() {}
