//! What a render state was rendered with: every setting that changes the image a seed gives,
//! written to and read from the state file's text metadata.

use std::collections::BTreeMap;

use clap::ValueEnum;

use crate::integrators::{Algorithm, IntegratorOptions, SamplerKind};

/// Every setting that changes the estimator (and so the image a seed gives): two states can
/// be merged, and a state resumed, only with equal settings. How the work is scheduled
/// (threads, scheduler, samples per frame, backend) is not among them.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderSettings {
    /// The light transport algorithm.
    pub algorithm: Algorithm,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// The file's camera rendered from (`vcm render --camera`), `None` for the default.
    pub camera: Option<String>,
    /// Seed, sampler, path length, connections, light paths, merge radius and its reduction,
    /// pruning.
    pub options: IntegratorOptions,
}

/// Every setting of [`RenderSettings`]: its key in the state file's metadata and the option
/// that gives it (`vcm render --max-depth` has the id `max_depth`, as the viewer's option and
/// the Python keyword), in the order messages list them.
pub const SETTINGS: [(&str, &str); 12] = [
    ("algorithm", "algo"),
    ("width", "width"),
    ("height", "height"),
    ("camera", "camera"),
    ("seed", "seed"),
    ("sampler", "sampler"),
    ("max_depth", "max_depth"),
    ("connections", "connections"),
    ("light_paths", "light_paths"),
    ("radius", "radius"),
    ("alpha", "alpha"),
    ("no_prune", "no_prune"),
];

/// The metadata keys of [`SETTINGS`].
pub const SETTING_KEYS: [&str; 12] = column(0);

/// The options of [`SETTINGS`] (for clap's `conflicts_with_all`, which takes an array).
pub const SETTING_OPTIONS: [&str; 12] = column(1);

/// Column `index` (0: keys, 1: options) of [`SETTINGS`].
const fn column(index: usize) -> [&'static str; 12] {
    let mut names = [""; 12];
    let mut i = 0;
    while i < names.len() {
        names[i] = if index == 0 {
            SETTINGS[i].0
        } else {
            SETTINGS[i].1
        };
        i += 1;
    }
    names
}

/// The name clap gives a value of a `ValueEnum` on the command line.
fn enum_name(value: &impl ValueEnum) -> String {
    value
        .to_possible_value()
        .map_or_else(String::new, |v| v.get_name().to_string())
}

impl RenderSettings {
    /// The settings as text, one entry per key of [`SETTING_KEYS`]: numbers as Rust prints
    /// them (floats in their shortest form that reads back exactly), `max_depth` and `camera`
    /// as `none` when not set.
    pub fn to_metadata(&self) -> BTreeMap<String, String> {
        let o = &self.options;
        let values = [
            self.algorithm.name().to_string(),
            self.width.to_string(),
            self.height.to_string(),
            self.camera.clone().unwrap_or_else(|| "none".into()),
            o.seed.to_string(),
            enum_name(&o.sampler),
            o.max_depth.map_or_else(|| "none".into(), |d| d.to_string()),
            o.connections.to_string(),
            o.light_paths.to_string(),
            o.radius.to_string(),
            o.alpha.to_string(),
            o.no_prune.to_string(),
        ];
        SETTING_KEYS
            .iter()
            .map(|k| k.to_string())
            .zip(values)
            .collect()
    }

    /// Reads the settings back from `metadata`; the error names the missing or unreadable
    /// entry.
    pub fn from_metadata(metadata: &BTreeMap<String, String>) -> Result<RenderSettings, String> {
        let get = |key: &str| {
            metadata
                .get(key)
                .map(String::as_str)
                .ok_or_else(|| format!("the setting `{key}` is missing"))
        };
        fn parse<T: std::str::FromStr>(key: &str, text: &str) -> Result<T, String> {
            text.parse()
                .map_err(|_| format!("the setting `{key}` has the unreadable value `{text}`"))
        }
        let optional = |key: &str| -> Result<Option<String>, String> {
            let text = get(key)?;
            Ok((text != "none").then(|| text.to_string()))
        };
        let algorithm = Algorithm::from_str(get("algorithm")?, false)
            .map_err(|_| format!("unknown algorithm `{}`", get("algorithm").unwrap_or("")))?;
        let sampler = SamplerKind::from_str(get("sampler")?, false)
            .map_err(|_| format!("unknown sampler `{}`", get("sampler").unwrap_or("")))?;
        let max_depth = match optional("max_depth")? {
            Some(depth) => Some(parse("max_depth", &depth)?),
            None => None,
        };
        // States written before the setting existed rendered one light path per pixel.
        let light_paths = match metadata.get("light_paths") {
            None => 1.0,
            Some(n) => parse("light_paths", n)?,
        };
        Ok(RenderSettings {
            algorithm,
            width: parse("width", get("width")?)?,
            height: parse("height", get("height")?)?,
            camera: optional("camera")?,
            options: IntegratorOptions {
                seed: parse("seed", get("seed")?)?,
                sampler,
                max_depth,
                connections: parse("connections", get("connections")?)?,
                light_paths,
                radius: parse("radius", get("radius")?)?,
                alpha: parse("alpha", get("alpha")?)?,
                no_prune: parse("no_prune", get("no_prune")?)?,
            },
        })
    }

    /// Each setting that differs from `other`'s, as (key, ours, theirs), in
    /// [`SETTING_KEYS`] order.
    pub fn differences(&self, other: &RenderSettings) -> Vec<(&'static str, String, String)> {
        let (ours, theirs) = (self.to_metadata(), other.to_metadata());
        SETTING_KEYS
            .iter()
            .filter(|&&key| ours[key] != theirs[key])
            .map(|&key| (key, ours[key].clone(), theirs[key].clone()))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrators::MergeRadius;

    fn example() -> RenderSettings {
        RenderSettings {
            algorithm: Algorithm::Vcm,
            width: 64,
            height: 48,
            camera: Some("Top view".into()),
            options: IntegratorOptions {
                seed: u64::MAX,
                sampler: SamplerKind::Independent,
                max_depth: Some(7),
                connections: 3,
                light_paths: 2.5,
                radius: MergeRadius::SceneFraction(0.003_141_592_7),
                alpha: 0.75,
                no_prune: true,
            },
        }
    }

    #[test]
    fn settings_round_trip_through_text_exactly() {
        let settings = example();
        assert_eq!(
            RenderSettings::from_metadata(&settings.to_metadata()),
            Ok(settings.clone())
        );
        let mut in_pixels = example();
        in_pixels.options.radius = MergeRadius::Pixels(1.618_034);
        let text = in_pixels.to_metadata();
        assert_eq!(text["radius"], "1.618034px");
        assert_eq!(RenderSettings::from_metadata(&text), Ok(in_pixels));
        let defaults = RenderSettings {
            camera: None,
            options: IntegratorOptions::default(),
            ..settings
        };
        let text = defaults.to_metadata();
        assert_eq!(text["camera"], "none");
        assert_eq!(text["max_depth"], "none");
        assert_eq!(text["light_paths"], "1");
        assert_eq!(RenderSettings::from_metadata(&text), Ok(defaults.clone()));
        // A state written before light paths were a setting rendered one per pixel.
        let mut older = text;
        older.remove("light_paths");
        assert_eq!(RenderSettings::from_metadata(&older), Ok(defaults));
    }

    #[test]
    fn differences_name_each_setting() {
        let a = example();
        let mut b = example();
        b.options.seed = 3;
        b.options.alpha = 0.5;
        let differences = a.differences(&b);
        let keys: Vec<_> = differences.iter().map(|d| d.0).collect();
        assert_eq!(keys, ["seed", "alpha"]);
        assert_eq!(differences[1].1, "0.75");
        assert!(a.differences(&a).is_empty());
    }

    #[test]
    fn missing_and_unreadable_settings_are_named() {
        let mut text = example().to_metadata();
        text.remove("seed");
        let error = RenderSettings::from_metadata(&text).unwrap_err();
        assert!(error.contains("`seed`"), "{error}");
        let mut text = example().to_metadata();
        text.insert("connections".into(), "many".into());
        let error = RenderSettings::from_metadata(&text).unwrap_err();
        assert!(
            error.contains("`connections`") && error.contains("many"),
            "{error}"
        );
        let mut text = example().to_metadata();
        text.insert("light_paths".into(), "lots".into());
        let error = RenderSettings::from_metadata(&text).unwrap_err();
        assert!(error.contains("`light_paths`"), "{error}");
        let mut text = example().to_metadata();
        text.insert("algorithm".into(), "mlt".into());
        assert!(RenderSettings::from_metadata(&text).is_err());
    }
}
