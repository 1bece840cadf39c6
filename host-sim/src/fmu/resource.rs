//! The model an FMU carries in `resources/model.toml`: the scene's model
//! part (run, backbone, effects, temperature history) with a placeholder
//! profile, since the co-simulation master supplies the displacement.

use std::path::{Path, PathBuf};

use sha2::{Digest, Sha256};

use super::FmuError;
use crate::scene::{LoadOptions, Scene};

/// The model's file name in the FMU's `resources/` folder.
pub const RESOURCE_FILE: &str = "model.toml";

/// The tables of a scene the FMU does not use: the master drives the
/// displacement, so the profile, the rig's ADC and the trace settings have
/// no meaning inside it.
const DROPPED: [&str; 3] = ["profile", "adc", "output"];

/// A model ready for an FMU: the resource text, the scene it reads as, and
/// the GUID that ties the two to one model description.
#[derive(Debug, Clone)]
pub struct FmuModel {
    /// The text of `resources/model.toml`.
    pub text: String,
    /// That text, read and checked.
    pub scene: Scene,
    /// The FMU's GUID: a digest of the text and of this crate's version.
    pub guid: String,
    /// Duration of the source scene's profile, s (the default experiment's
    /// stop time), when made from a scene.
    pub stop_time: Option<f64>,
}

impl FmuModel {
    /// The model of the scene (or identified `model.toml`) at `path`, in
    /// `options.number` instead of the scene's own working type when
    /// given. The scene is read and checked whole first, so its errors
    /// point at its own lines.
    pub fn from_scene(path: &Path, options: LoadOptions) -> Result<Self, FmuError> {
        let source = Scene::load_with(path, options).map_err(|e| FmuError::Scene(Box::new(e)))?;
        if source.oscillator.is_some() {
            return Err(FmuError::Unsupported(format!(
                "{}: an [oscillator] scene is driven by a force; the FMU's input is the \
                 bushing's displacement (remove [oscillator])",
                path.display()
            )));
        }
        let text = crate::records::read_limited(path, crate::scene::MAX_SCENE_BYTES)
            .map_err(|e| FmuError::Io(format!("{}: {e}", path.display())))?;
        let mut table: toml::Table = toml::from_str(&text)
            .map_err(|e| FmuError::Unsupported(format!("{}: {e}", path.display())))?;
        for key in DROPPED {
            table.remove(key);
        }
        if let Some(toml::Value::Table(run)) = table.get_mut("run") {
            run.insert(
                "number".into(),
                toml::Value::String(source.number.name().into()),
            );
        }
        let mut profile = toml::Table::new();
        profile.insert("type".into(), "hold".into());
        profile.insert("duration_s".into(), 1.0.into());
        table.insert("profile".into(), toml::Value::Table(profile));
        let body = toml::to_string(&table)
            .map_err(|e| FmuError::Unsupported(format!("{}: {e}", path.display())))?;
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().replace(['\n', '\r'], " "))
            .unwrap_or_default();
        let text = format!(
            "# The model of this FMU, written by `bushing-sim fmu` from {name}.\n\
             # The master drives the displacement: [profile] is a placeholder.\n\n{body}"
        );
        let mut model = Self::parse(&text, RESOURCE_FILE)?;
        model.stop_time = Some(source.steps() as f64 * source.dt);
        Ok(model)
    }

    /// Reads a resource text (`file` names it in errors).
    pub fn parse(text: &str, file: &str) -> Result<Self, FmuError> {
        let scene = Scene::parse_with(file, text, Path::new(""), LoadOptions::default())
            .map_err(|e| FmuError::Scene(Box::new(e)))?;
        if scene.oscillator.is_some() {
            return Err(FmuError::Unsupported(format!(
                "{file}: an [oscillator] model is driven by a force, not a displacement"
            )));
        }
        Ok(Self {
            guid: guid(text),
            text: text.to_string(),
            scene,
            stop_time: None,
        })
    }

    /// Reads `resources/model.toml` from the FMU's resource folder (at
    /// most [`crate::scene::MAX_SCENE_BYTES`], a regular file).
    pub fn load(resources: &Path) -> Result<Self, FmuError> {
        let path = resources.join(RESOURCE_FILE);
        let text = crate::records::read_limited(&path, crate::scene::MAX_SCENE_BYTES)
            .map_err(|e| FmuError::Io(format!("{}: {e}", path.display())))?;
        Self::parse(&text, &path.display().to_string())
    }
}

/// The GUID of a resource text: the first 128 bits of the SHA-256 of this
/// crate's version and the text, in the `{8-4-4-4-12}` form.
pub fn guid(text: &str) -> String {
    let mut hash = Sha256::new();
    hash.update(env!("CARGO_PKG_VERSION").as_bytes());
    hash.update([0]);
    hash.update(text.as_bytes());
    let hex: String = hash.finalize()[..16]
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect();
    format!(
        "{{{}-{}-{}-{}-{}}}",
        &hex[..8],
        &hex[8..12],
        &hex[12..16],
        &hex[16..20],
        &hex[20..]
    )
}

/// The folder an FMI `fmuResourceLocation` names: a `file:` URI (with an
/// empty or `localhost` host, percent-escapes decoded), or, as some
/// masters pass it, a plain absolute path.
pub fn resource_dir(location: &str) -> Result<PathBuf, FmuError> {
    if location.starts_with('/') {
        return Ok(PathBuf::from(location));
    }
    let url = url::Url::parse(location).map_err(|e| {
        FmuError::Resource(format!(
            "the resource location {location:?} is not a URI: {e}"
        ))
    })?;
    if url.scheme() != "file" {
        return Err(FmuError::Resource(format!(
            "the resource location {location:?} is not a file: URI"
        )));
    }
    url.to_file_path().map_err(|()| {
        FmuError::Resource(format!(
            "the resource location {location:?} names no local folder"
        ))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resource_locations() {
        for (uri, path) in [
            ("file:///tmp/fmu/resources", "/tmp/fmu/resources"),
            ("file:///tmp/fmu/resources/", "/tmp/fmu/resources/"),
            ("file:/tmp/fmu/resources", "/tmp/fmu/resources"),
            ("file://localhost/tmp/a%20b/resources", "/tmp/a b/resources"),
            ("/tmp/plain", "/tmp/plain"),
        ] {
            assert_eq!(resource_dir(uri).unwrap(), PathBuf::from(path), "{uri}");
        }
        for bad in [
            "http://example.com/r",
            "file://otherhost/r",
            "relative/path",
            "",
        ] {
            assert!(
                matches!(resource_dir(bad), Err(FmuError::Resource(_))),
                "{bad}"
            );
        }
    }

    #[test]
    fn guid_form_and_dependence() {
        let g = guid("a");
        assert_eq!(g.len(), 38);
        assert!(g.starts_with('{') && g.ends_with('}'));
        assert_eq!(g.matches('-').count(), 4);
        assert_ne!(g, guid("b"));
        assert_eq!(g, guid("a"));
    }
}
