//! Scene files (TOML): schema, validation with key-path errors, and building
//! a run from them.
//!
//! Parsing goes through `serde_path_to_error`, so unknown keys, missing keys and
//! wrong types name their key path; [`Scene::validate`] then checks ranges and
//! cross-references and names the offending key with its allowed range.

mod build;
mod membrane_elements;
mod multiphase;
mod schema;

pub use build::{
    build_coupled_run, build_fluid_run, build_implicit_run, build_solid_run, fill_particles,
    grid_of,
};
pub use membrane_elements::*;
pub use multiphase::*;
pub use schema::*;

use crate::error::SceneError;

/// Parses and validates a scene from TOML text.
pub fn parse(text: &str) -> Result<Scene, SceneError> {
    let de = toml::Deserializer::parse(text)
        .map_err(|e| SceneError::new("<toml>", format!("not valid TOML: {}", e.message())))?;
    let scene: Scene = serde_path_to_error::deserialize(de).map_err(|e| {
        let path = e.path().to_string();
        let inner = e.into_inner();
        SceneError::new(
            if path == "." {
                "<root>".to_string()
            } else {
                path
            },
            inner.message().to_string(),
        )
    })?;
    scene.validate()?;
    Ok(scene)
}

/// Reads, parses and validates a scene file.
pub fn load(path: &std::path::Path) -> Result<Scene, SceneError> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| SceneError::new("<file>", format!("cannot read {}: {e}", path.display())))?;
    parse(&text)
}
