//! Materials in messages: by their scene name and their `materials[i]`
//! index, never by an internal index (ICE numbers its fluids first, a
//! coupled run its solid fields after them).

use super::Scene;

impl Scene {
    /// `` `air` (materials[1]) `` for a material of the scene; the name in
    /// backticks alone for another.
    pub fn material_label(&self, name: &str) -> String {
        match self.materials.iter().position(|m| m.name == name) {
            Some(i) => format!("`{name}` (materials[{i}])"),
            None => format!("`{name}`"),
        }
    }

    /// `text` with every ``material `NAME` `` of a scene material followed
    /// by its index, `` material `NAME` (materials[i]) `` (once: a labelled
    /// one is left as it is).
    pub fn label_materials(&self, text: &str) -> String {
        const KEY: &str = "material `";
        let mut out = String::with_capacity(text.len() + 32);
        let mut rest = text;
        while let Some(at) = rest.find(KEY) {
            let (head, tail) = rest.split_at(at + KEY.len());
            out.push_str(head);
            let Some(end) = tail.find('`') else {
                rest = tail;
                continue;
            };
            let name = &tail[..end];
            out.push_str(name);
            out.push('`');
            rest = &tail[end + 1..];
            let labelled = rest.starts_with(" (materials[");
            if let Some(i) = self.materials.iter().position(|m| m.name == name) {
                if !labelled {
                    out.push_str(&format!(" (materials[{i}])"));
                }
            }
        }
        out.push_str(rest);
        out
    }
}
