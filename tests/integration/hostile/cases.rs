//! The generator of hostile input (issue 56): scene files and options of every class a hostile
//! user tried, written into a temporary folder. Each case says what a correct `vcm` does with
//! it: refuses it with a message holding a given phrase, renders it, or either.

use std::path::Path;
use std::process::Command;

use glam::Vec3;
use vcm_rs::scene::testing::{
    data_uri, deep_chain, doubling_chain, exr_claiming, glb, png_claiming, triangle_positions,
};
use vcm_rs::vcm::image_io::RgbImage;

/// What a correct `vcm` does with a case.
#[derive(Clone, Copy, Debug)]
pub enum Expect {
    /// Refuses it: exit status 1 (2 for a command-line usage error) and this phrase in the
    /// message.
    Error(&'static str),
    /// Renders it (or, for `vcm info`, describes it): exit status 0.
    Success,
    /// Either a clear error or success (what the specification leaves open).
    Either,
}

/// One run of `vcm`.
pub struct Case {
    /// The class of hostile input, for the figures.
    pub class: &'static str,
    /// What the case is, for messages.
    pub name: String,
    /// The arguments after `vcm`.
    pub args: Vec<String>,
    pub expect: Expect,
}

/// One triangle in the z = 0 plane, lit from above by a point light, seen by a camera: the
/// document every scene case distorts. `nodes` replaces its node list (node 0 draws the
/// triangle, the scene's root is node 0), `material` its material, `camera` its
/// perspective camera, `buffer` its buffer.
struct Document<'a> {
    nodes: &'a str,
    material: &'a str,
    camera: &'a str,
    buffer: &'a str,
    extra: &'a str,
}

impl Default for Document<'_> {
    fn default() -> Self {
        Document {
            nodes: r#"[{"mesh": 0, "children": [1, 2]},
                       {"camera": 0, "translation": [0.3, 0.3, 2]},
                       {"extensions": {"KHR_lights_punctual": {"light": 0}},
                        "translation": [0.3, 0.3, 1]}]"#,
            material: r#"{"pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1]}}"#,
            camera: r#"{"yfov": 0.8, "znear": 0.01, "aspectRatio": 1.0}"#,
            buffer: "",
            extra: "",
        }
    }
}

impl Document<'_> {
    fn json(&self) -> String {
        let buffer = if self.buffer.is_empty() {
            format!(
                r#"{{"byteLength": 36, "uri": "{}"}}"#,
                data_uri(&triangle_positions())
            )
        } else {
            self.buffer.to_string()
        };
        format!(
            r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0]}}],
            "extensionsUsed": ["KHR_lights_punctual"],
            "extensions": {{"KHR_lights_punctual": {{"lights": [{{"type": "point",
                "intensity": 5}}]}}}},
            "nodes": {nodes},
            "cameras": [{{"type": "perspective", "perspective": {camera}}}],
            "materials": [{material}],
            "buffers": [{buffer}],
            "bufferViews": [{{"buffer": 0, "byteLength": 36}}],
            "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 3,
                "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}}],
            "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}},
                "material": 0}}]}}] {extra}}}"#,
            nodes = self.nodes,
            camera = self.camera,
            material = self.material,
            extra = self.extra,
        )
    }
}

/// A valid OBJ triangle lit by an emissive material, and its MTL library.
const OBJ: &str = "mtllib tri.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl glow\nf 1 2 3\n";
const MTL: &str = "newmtl glow\nKd 0.5 0.5 0.5\nKe 1 1 1\n";

/// Makes a FIFO at `path` (it blocks a reader that opens it).
fn mkfifo(path: &Path) {
    let made = Command::new("mkfifo").arg(path).status();
    assert!(made.is_ok_and(|s| s.success()), "mkfifo {}", path.display());
}

/// Makes a character device like /dev/zero (major 1, minor 5) at `path`; only root may, so
/// `false` elsewhere. Never the real device: a node of its own in the temporary folder.
fn mknod_zero(path: &Path) -> bool {
    let made = Command::new("mknod")
        .arg(path)
        .args(["c", "1", "5"])
        .output();
    made.is_ok_and(|o| o.status.success())
}

/// Collects the cases: scene files are written into `dir`, each run by `vcm info` and by a
/// small `vcm render` (16 pixels wide, 1 sample per pixel, output in `dir`).
pub struct Generator<'a> {
    dir: &'a Path,
    pub cases: Vec<Case>,
}

impl<'a> Generator<'a> {
    pub fn new(dir: &'a Path) -> Self {
        Generator {
            dir,
            cases: Vec::new(),
        }
    }

    fn path(&self, name: &str) -> String {
        self.dir.join(name).to_str().expect("a UTF-8 folder").into()
    }

    /// A scene file `name` of `bytes`, run by `info` and `render`.
    fn scene(&mut self, class: &'static str, name: &str, bytes: &[u8], expect: Expect) {
        std::fs::write(self.dir.join(name), bytes).unwrap();
        self.run_scene(class, name, &[], expect);
    }

    /// The scene file `name` (already in the folder), run by `info` and `render` with `extra`
    /// arguments.
    fn run_scene(&mut self, class: &'static str, name: &str, extra: &[&str], expect: Expect) {
        let scene = self.path(name);
        let out = self.path(&format!("{}.exr", self.cases.len()));
        let render = ["render", &scene, "--width", "16", "--spp", "1", "-o", &out];
        let info = ["info", &scene];
        for args in [&render[..], &info[..]] {
            self.cases.push(Case {
                class,
                name: format!("{} {name} {}", args[0], extra.join(" ")),
                args: args.iter().chain(extra).map(|s| s.to_string()).collect(),
                expect,
            });
        }
    }

    /// `vcm render` of the Cornell box with `args` (16 pixels wide and 1 sample per pixel
    /// unless they say otherwise).
    fn options(&mut self, class: &'static str, args: &[&str], expect: Expect) {
        let out = self.path(&format!("{}.exr", self.cases.len()));
        let mut all = vec!["render", "scenes/cornell-box.gltf"];
        if !args.contains(&"--time") {
            all.extend(["--spp", "1"]);
        }
        if !args.contains(&"--width") {
            all.extend(["--width", "16"]);
        }
        all.extend(["-o", &out]);
        all.extend(args);
        self.cases.push(Case {
            class,
            name: args.join(" "),
            args: all.iter().map(|s| s.to_string()).collect(),
            expect,
        });
    }

    /// Every class of hostile input.
    pub fn all(mut self) -> Vec<Case> {
        self.malformed();
        self.truncated();
        self.huge_declared();
        self.graphs();
        self.out_of_range();
        self.device_files();
        self.hostile_options();
        self.hostile_images();
        self.cases
    }

    fn malformed(&mut self) {
        let class = "malformed";
        let valid = Document::default().json();
        self.scene(class, "valid.gltf", valid.as_bytes(), Expect::Success);
        let documents = [
            ("not-json.gltf", "this is not JSON".to_string()),
            ("empty.gltf", String::new()),
            ("no-asset.gltf", r#"{"scenes": [{"nodes": []}]}"#.into()),
            (
                "nodes-not-a-list.gltf",
                valid.replacen(r#""nodes": [{"mesh""#, r#""nodes": 5, "x": [{"mesh""#, 1),
            ),
            (
                "bad-accessor.gltf",
                valid.replace(r#""POSITION": 0"#, r#""POSITION": 7"#),
            ),
            ("bad-component.gltf", valid.replace("5126", "9999")),
            (
                "bad-root.gltf",
                valid.replace(r#""nodes": [0]"#, r#""nodes": [99]"#),
            ),
            (
                "negative-count.gltf",
                valid.replace(r#""count": 3"#, r#""count": -3"#),
            ),
            ("bad-base64.gltf", valid.replace("base64,", "base64,!!!")),
        ];
        for (name, json) in documents {
            self.scene(class, name, json.as_bytes(), Expect::Error("error:"));
        }
        let bad_obj = [
            ("short-vertex.obj", "v 1 2\nf 1 2 3\n"),
            (
                "index-out-of-range.obj",
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 999999\n",
            ),
            ("index-zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n"),
            ("garbage.obj", "\u{0}\u{1}\u{2}binary\u{ff}garbage\n"),
        ];
        for (name, text) in bad_obj {
            self.scene(class, name, text.as_bytes(), Expect::Either);
        }
        std::fs::write(self.dir.join("tri.mtl"), MTL).unwrap();
        self.scene(class, "valid.obj", OBJ.as_bytes(), Expect::Success);
        let odd_mtl = "newmtl glow\nKd nan inf -1\nKe 1e39 1 1\nNs -5\nmap_Kd missing.png\n";
        std::fs::write(self.dir.join("odd.mtl"), odd_mtl).unwrap();
        let odd_obj = OBJ.replace("tri.mtl", "odd.mtl");
        self.scene(class, "odd-mtl.obj", odd_obj.as_bytes(), Expect::Either);
    }

    fn truncated(&mut self) {
        let class = "truncated";
        let json = Document::default().json();
        let binary = glb(&json, &[]);
        std::fs::write(self.dir.join("valid.glb"), &binary).unwrap();
        self.run_scene(class, "valid.glb", &[], Expect::Success);
        for fraction in [1, 3, 5, 7, 9] {
            let cut = json.len() * fraction / 10;
            let name = format!("cut-{fraction}.gltf");
            self.scene(
                class,
                &name,
                &json.as_bytes()[..cut],
                Expect::Error("error:"),
            );
            let cut = binary.len() * fraction / 10;
            let name = format!("cut-{fraction}.glb");
            self.scene(class, &name, &binary[..cut], Expect::Error("error:"));
        }
        self.scene(
            class,
            "cut.obj",
            &OBJ.as_bytes()[..OBJ.len() - 4],
            Expect::Either,
        );
    }

    fn huge_declared(&mut self) {
        let class = "huge-declared";
        let buffers = [
            (
                "huge-buffer.gltf",
                format!(
                    r#"{{"byteLength": 1000000000000000, "uri": "{}"}}"#,
                    data_uri(&triangle_positions())
                ),
            ),
            (
                "huge-buffer-file.gltf",
                r#"{"byteLength": 1000000000000, "uri": "tri.bin"}"#.into(),
            ),
        ];
        std::fs::write(self.dir.join("tri.bin"), triangle_positions()).unwrap();
        for (name, buffer) in buffers {
            let json = Document {
                buffer: &buffer,
                ..Document::default()
            }
            .json();
            self.scene(class, name, json.as_bytes(), Expect::Error("error:"));
        }
        let huge_count = Document::default()
            .json()
            .replace(r#""count": 3"#, r#""count": 4000000000"#);
        self.scene(
            class,
            "huge-count.gltf",
            huge_count.as_bytes(),
            Expect::Error("error:"),
        );
        // A GLB whose header and chunk claim 4 GB.
        let mut binary = glb(&Document::default().json(), &triangle_positions());
        binary[8..12].copy_from_slice(&u32::MAX.to_le_bytes());
        self.scene(class, "huge-length.glb", &binary, Expect::Error("error:"));
        // Images whose headers claim 16384² (EXR environment) and 20000² (PNG texture)
        // texels in a few hundred bytes.
        std::fs::write(self.dir.join("sky.exr"), exr_claiming(16384, 16384)).unwrap();
        let sky = Document {
            extra: r#", "extensionsUsed": ["KHR_lights_punctual", "VCM_environment"],
                "extensions": {"VCM_environment": {"image": "sky.exr"}}"#,
            ..Document::default()
        }
        .json()
        .replacen(r#""extensionsUsed": ["KHR_lights_punctual"],"#, "", 1)
        .replacen(
            r#""extensions": {"KHR_lights_punctual": {"lights": [{"type": "point",
                "intensity": 5}]}},"#,
            "",
            1,
        );
        self.scene(class, "huge-sky.gltf", sky.as_bytes(), Expect::Either);
        std::fs::write(self.dir.join("huge.png"), png_claiming(20000, 20000)).unwrap();
        let textured = Document {
            material: r#"{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}"#,
            extra: r#", "images": [{"uri": "huge.png"}], "textures": [{"source": 0}]"#,
            ..Document::default()
        }
        .json();
        self.scene(
            class,
            "huge-texture.gltf",
            textured.as_bytes(),
            Expect::Error("error:"),
        );
    }

    fn graphs(&mut self) {
        let class = "node graphs";
        let cases = [
            (
                "cycle.gltf",
                r#"[{"mesh": 0, "children": [1]}, {"children": [0]}]"#.to_string(),
                Expect::Error("error:"),
            ),
            (
                "self-child.gltf",
                r#"[{"mesh": 0, "children": [0]}]"#.into(),
                Expect::Error("error:"),
            ),
            ("deep-chain.gltf", deep_chain(100_000), Expect::Either),
            ("doubling-21.gltf", doubling_chain(21), Expect::Either),
            (
                "doubling-30.gltf",
                doubling_chain(30),
                Expect::Error("error:"),
            ),
            (
                "doubling-64.gltf",
                doubling_chain(64),
                Expect::Error("error:"),
            ),
        ];
        for (name, nodes, expect) in cases {
            let json = Document {
                nodes: &nodes,
                ..Document::default()
            }
            .json();
            self.scene(class, name, json.as_bytes(), expect);
        }
    }

    fn out_of_range(&mut self) {
        let class = "out of range";
        let materials = [
            r#"{"pbrMetallicRoughness": {"roughnessFactor": -1, "metallicFactor": -5}}"#,
            r#"{"pbrMetallicRoughness": {"baseColorFactor": [100, 100, 100, 1]}}"#,
            r#"{"extensions": {"KHR_materials_transmission": {"transmissionFactor": 5}}}"#,
            r#"{"extensions": {"KHR_materials_ior": {"ior": 0.5}}}"#,
            r#"{"emissiveFactor": [1e38, 1e38, 1e38], "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 1e38}}}"#,
        ];
        for (i, material) in materials.into_iter().enumerate() {
            let json = Document {
                material,
                ..Document::default()
            }
            .json();
            self.scene(
                class,
                &format!("material-{i}.gltf"),
                json.as_bytes(),
                Expect::Either,
            );
        }
        let cameras = [
            r#"{"yfov": 0.8, "znear": 0.01, "aspectRatio": 0.000001}"#,
            r#"{"yfov": 0.8, "znear": 0.01, "aspectRatio": 1000000}"#,
            r#"{"yfov": 0.8, "znear": 0.01, "aspectRatio": 0}"#,
            r#"{"yfov": 0.8, "znear": 0.01, "aspectRatio": -1}"#,
            r#"{"yfov": 0, "znear": 0.01}"#,
            r#"{"yfov": 10, "znear": -1}"#,
        ];
        for (i, camera) in cameras.into_iter().enumerate() {
            let json = Document {
                camera,
                ..Document::default()
            }
            .json();
            self.scene(
                class,
                &format!("camera-{i}.gltf"),
                json.as_bytes(),
                Expect::Either,
            );
        }
        // Vertices at 1e38 and NaN bounds.
        let far: [f32; 9] = [1e38, 0.0, 0.0, -1e38, 1e38, 0.0, 0.0, -1e38, 1e38];
        let far: Vec<u8> = far.iter().flat_map(|f| f.to_le_bytes()).collect();
        let buffer = format!(r#"{{"byteLength": 36, "uri": "{}"}}"#, data_uri(&far));
        let json = Document {
            buffer: &buffer,
            ..Document::default()
        }
        .json();
        self.scene(class, "far-vertices.gltf", json.as_bytes(), Expect::Either);
        let transform = r#"[{"mesh": 0, "scale": [1e30, 1e30, 1e30], "children": [1]}, {"camera": 0, "translation": [0, 0, 2]}]"#;
        let json = Document {
            nodes: transform,
            ..Document::default()
        }
        .json();
        self.scene(class, "huge-scale.gltf", json.as_bytes(), Expect::Either);
    }

    fn device_files(&mut self) {
        let class = "device files";
        let with_uri = |uri: &str| {
            let buffer = format!(r#"{{"byteLength": 36, "uri": "{uri}"}}"#);
            Document {
                buffer: &buffer,
                ..Document::default()
            }
            .json()
        };
        mkfifo(&self.dir.join("fifo.bin"));
        self.scene(
            class,
            "fifo-buffer.gltf",
            with_uri("fifo.bin").as_bytes(),
            Expect::Error("not a regular file"),
        );
        mkfifo(&self.dir.join("fifo.gltf"));
        self.run_scene(class, "fifo.gltf", &[], Expect::Error("not a regular file"));
        // Outside the scene's folder: refused without being opened (confinement).
        for uri in ["/dev/zero", "../../../../../../dev/zero", "/etc/passwd"] {
            let name = format!("outside-{}.gltf", self.cases.len());
            self.scene(
                class,
                &name,
                with_uri(uri).as_bytes(),
                Expect::Error("outside"),
            );
        }
        let mtl = "mtllib ../../../../../../etc/passwd\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
        self.scene(class, "outside-mtl.obj", mtl.as_bytes(), Expect::Either);
        // A node like /dev/zero made in the folder (as root only): never read to the end,
        // also where files outside the folder are allowed.
        if mknod_zero(&self.dir.join("zero.bin")) {
            let json = with_uri("zero.bin");
            std::fs::write(self.dir.join("zero-buffer.gltf"), json).unwrap();
            self.run_scene(
                class,
                "zero-buffer.gltf",
                &[],
                Expect::Error("not a regular file"),
            );
            let allowed = ["--allow-outside-files"];
            self.run_scene(
                class,
                "zero-buffer.gltf",
                &allowed,
                Expect::Error("not a regular file"),
            );
        }
    }

    fn hostile_options(&mut self) {
        let cases: [(&[&str], Expect); 16] = [
            (
                &["--width", "30000", "--height", "30000"],
                Expect::Error("lower --width or --height"),
            ),
            (
                &["--width", "4294967295", "--height", "4294967295"],
                Expect::Error("error:"),
            ),
            (&["--spp-per-frame", "100000"], Expect::Success),
            (
                &["--spp-per-frame", "100000", "--algo", "vcm"],
                Expect::Success,
            ),
            (
                &["--time", "1", "--spp-per-frame", "100000", "--algo", "vcm"],
                Expect::Error("lower --spp-per-frame"),
            ),
            // The path tracer fits the 4 GiB limit in tiles, not as one batch of 12 M paths.
            (
                &[
                    "--algo",
                    "pt",
                    "--width",
                    "3500",
                    "--height",
                    "3500",
                    "--scheduler",
                    "none",
                ],
                Expect::Error("lower the paths in flight"),
            ),
            (
                &["--algo", "bpt", "--connections", "1000000"],
                Expect::Error("--connections"),
            ),
            (&["--algo", "bpt", "--connections", "1024"], Expect::Success),
            (&["--threads", "10000"], Expect::Error("--threads")),
            (&["--threads", "0"], Expect::Error("--threads")),
            (&["--tile-merge", "NaN"], Expect::Error("tile merge")),
            (&["--tile-merge", "2"], Expect::Error("tile merge")),
            (&["--tile-size", "4294967295"], Expect::Success),
            (
                &["--scheduler", "queue", "--queues", "100000"],
                Expect::Success,
            ),
            (&["--time", "-1"], Expect::Error("--time")),
            (
                &["--radius", "inf", "--algo", "vcm"],
                Expect::Error("radius"),
            ),
        ];
        for (args, expect) in cases {
            self.options("options", args, expect);
        }
    }

    fn hostile_images(&mut self) {
        let nan = RgbImage {
            width: 16,
            height: 16,
            pixels: (0..256)
                .map(|i| if i % 100 == 7 { Vec3::NAN } else { Vec3::ONE })
                .collect(),
        };
        let nan_path = self.path("nan.exr");
        nan.write_exr(Path::new(&nan_path)).unwrap();
        let finite = RgbImage {
            pixels: vec![Vec3::ONE; 256],
            ..nan
        };
        let finite_path = self.path("finite.exr");
        finite.write_exr(Path::new(&finite_path)).unwrap();
        let huge_path = self.path("huge.exr");
        std::fs::write(&huge_path, exr_claiming(16384, 16384)).unwrap();
        let class = "images";
        let compare = [
            (
                &nan_path,
                &finite_path,
                Expect::Error("3 of 256 pixels are not finite"),
            ),
            (
                &finite_path,
                &nan_path,
                Expect::Error("3 of 256 pixels are not finite"),
            ),
            (&finite_path, &finite_path, Expect::Success),
            (&huge_path, &finite_path, Expect::Error("error:")),
        ];
        for (image, reference, expect) in compare {
            self.cases.push(Case {
                class,
                name: format!("compare {image} {reference}"),
                args: vec!["compare".into(), image.clone(), reference.clone()],
                expect,
            });
        }
        for (reference, expect) in [(&nan_path, "not finite"), (&huge_path, "error:")] {
            self.options(class, &["--reference", reference], Expect::Error(expect));
        }
    }
}
