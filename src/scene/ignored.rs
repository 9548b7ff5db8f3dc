//! Settings the scene's mode would ignore are rejected: a table that is
//! given but that no part of the chosen run reads names its key and the
//! mode (or the materials) that would use it.

use super::{MaterialKind, Mode, Scene};
use crate::error::SceneError;

impl Scene {
    /// Rejects tables of `raw` (the scene's TOML) that this scene's run
    /// would not read: `[coupling]` without solid and fluid materials,
    /// `[implicit]` outside `time.mode = "implicit"`, `[fluid.pressure]`
    /// outside `semi_implicit`, `[fluid]` without fluid materials in the
    /// cells and `[mpm]` without particles.
    pub(super) fn reject_ignored(&self, raw: &toml::Table) -> Result<(), SceneError> {
        let err = |k: &str, m: String| Err(SceneError::new(k, m));
        let in_cells = self.materials.iter().any(|m| m.in_cells());
        let particles = self.materials.iter().any(|m| m.on_particles());
        // Solids, membranes and gas points only (a later kind of material
        // may read [fluid] or [mpm]: it is not judged here).
        let known = |m: &super::MaterialSpec| {
            matches!(
                m.kind,
                MaterialKind::Solid | MaterialKind::Fluid | MaterialKind::Membrane
            )
        };
        let all_known = self.materials.iter().all(known);
        let coupled = self.materials.iter().any(|m| m.kind == MaterialKind::Solid) && in_cells;
        let what = if !self.membrane_elements.is_empty() {
            "a scene of membrane elements"
        } else if coupled {
            "a coupled scene"
        } else if in_cells {
            "a fluid-only scene"
        } else {
            "a scene without fluid in the cells"
        };
        let mode = self.time.mode.name();
        if raw.contains_key("coupling") && !coupled && all_known {
            return err(
                "coupling",
                format!(
                    "[coupling] is read only by coupled scenes (solid and fluid materials); \
                     this is {what}: remove it"
                ),
            );
        }
        if raw.contains_key("implicit") && self.time.mode != Mode::Implicit {
            return err(
                "implicit",
                format!(
                    "[implicit] is read only with time.mode = \"implicit\" (solid-only \
                     implicit MPM); this scene runs time.mode = \"{mode}\": remove it or \
                     change the mode"
                ),
            );
        }
        let fluid = raw.get("fluid").and_then(|v| v.as_table());
        let implicit_pressure =
            self.time.mode == Mode::SemiImplicit || (self.time.mode == Mode::Implicit && coupled);
        if fluid.is_some_and(|f| f.contains_key("pressure")) && !implicit_pressure {
            return err(
                "fluid.pressure",
                format!(
                    "[fluid.pressure] is read only with the implicit pressure solve \
                     (time.mode = \"semi_implicit\", or \"implicit\" in a coupled scene); \
                     this is {what} with time.mode = \"{mode}\": remove it or change the mode"
                ),
            );
        }
        if fluid.is_some() && !in_cells && all_known {
            return err(
                "fluid",
                format!(
                    "[fluid] is read only by scenes with fluid materials in the cells (type = \
                     \"fluid\", frame = \"cells\"); this is {what}: remove it"
                ),
            );
        }
        if raw.contains_key("mpm") && !particles && all_known && self.membrane_elements.is_empty() {
            return err(
                "mpm",
                format!(
                    "[mpm] is read only by scenes with particles (solids, membranes, gas \
                     points); this is {what}: remove it"
                ),
            );
        }
        Ok(())
    }
}
