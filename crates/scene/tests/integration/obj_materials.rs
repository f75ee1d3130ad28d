//! The OBJ/MTL → material mapping documented in `vcm_scene::loader::obj`.

use glam::{Vec2, Vec3, Vec4};
use vcm_scene::Scene;

const MTL: &str = "\
newmtl matte
Kd 0.5 0.25 0.125
newmtl plastic
Kd 0.5 0.5 0.5
Ks 0.5 0.25 0.25
Ns 98
newmtl metal
Kd 0 0 0
Ks 0.9 0.8 0.7
Ns 1000000
newmtl lamp
Kd 0 0 0
Ke 10 10 5
newmtl glass
illum 7
Ni 1.33
newmtl veil
d 0.25
newmtl textured
map_Kd checker.png
";

const OBJ: &str = "\
mtllib scene.mtl
v 0 0 0
v 1 0 0
v 0 1 0
vt 0 0
vt 1 0
vt 0 1
usemtl matte
f 1/1 2/2 3/3
usemtl plastic
f 1 2 3
usemtl metal
f 1 2 3
usemtl lamp
f 1 2 3
usemtl glass
f 1 2 3
usemtl veil
f 1 2 3
usemtl textured
f 1/1 2/2 3/3
";

fn write_scene(dir: &std::path::Path) -> std::path::PathBuf {
    std::fs::write(dir.join("scene.mtl"), MTL).unwrap();
    let obj = dir.join("scene.obj");
    std::fs::write(&obj, OBJ).unwrap();
    let checker = image::RgbaImage::from_fn(2, 2, |x, y| {
        let v = if (x + y) % 2 == 0 { 255 } else { 0 };
        image::Rgba([v, v, v, 255])
    });
    checker.save(dir.join("checker.png")).unwrap();
    obj
}

#[test]
fn mtl_parameters_map_onto_the_material_model() {
    let dir = tempfile::tempdir().unwrap();
    let scene = Scene::load(write_scene(dir.path())).unwrap();
    let by_name = |name: &str| scene.materials.iter().find(|m| m.name == name).unwrap();

    let matte = by_name("matte");
    assert_eq!(matte.base_color, Vec4::new(0.5, 0.25, 0.125, 1.0));
    assert_eq!(
        (matte.metallic, matte.specular, matte.roughness),
        (0.0, 0.0, 1.0)
    );

    let plastic = by_name("plastic");
    assert_eq!((plastic.metallic, plastic.specular), (0.0, 0.5));
    assert_eq!(plastic.specular_color, Vec3::new(1.0, 0.5, 0.5));
    // Ns 98: alpha = sqrt(2/100), roughness = alpha^(1/2).
    assert!((plastic.roughness - 0.02f32.sqrt().sqrt()).abs() < 1e-6);

    let metal = by_name("metal");
    assert_eq!(metal.metallic, 1.0);
    assert_eq!(metal.base_color, Vec4::new(0.9, 0.8, 0.7, 1.0));
    assert!(metal.roughness < 0.05);

    let lamp = by_name("lamp");
    assert_eq!(lamp.emission, Vec3::new(10.0, 10.0, 5.0));
    assert_eq!(scene.features.lights.area, 1);

    let glass = by_name("glass");
    assert_eq!(
        (glass.transmission, glass.ior, glass.thin_walled),
        (1.0, 1.33, false)
    );

    let veil = by_name("veil");
    assert_eq!((veil.transmission, veil.thin_walled), (0.75, true));

    let textured = by_name("textured");
    assert!(textured.base_color_texture.is_some());
    assert!(textured.double_sided);
    // OBJ's v axis points up; glTF's (and ours) down: vt (0,0) is the bottom-left corner.
    let last = scene.mesh.triangle_count() as u32 - 1;
    assert_eq!(
        scene.mesh.uv_at(last as usize, 0.0, 0.0),
        Vec2::new(0.0, 1.0)
    );
}

#[test]
fn a_missing_texture_or_material_library_is_reported() {
    let dir = tempfile::tempdir().unwrap();
    let obj = write_scene(dir.path());
    std::fs::remove_file(dir.path().join("checker.png")).unwrap();
    let message = Scene::load(&obj).unwrap_err().to_string();
    assert!(
        message.contains("checker.png") && message.contains("scene.obj"),
        "{message}"
    );

    std::fs::remove_file(dir.path().join("scene.mtl")).unwrap();
    let scene = Scene::load(&obj).unwrap();
    assert!(
        scene
            .warnings
            .iter()
            .any(|w| w.contains("material library"))
    );
    assert_eq!(scene.materials.len(), 1);
}
