//! One GLSL program object as capture knows it: not its code, but its inputs by name (the
//! attribute and uniform locations the program asked for, `glGetAttribLocation`,
//! `glGetUniformLocation`, `glBindAttribLocation`) and the values its uniforms were given. A
//! profile (`profile`) reads a draw's inputs by these names.

use std::collections::HashMap;

/// A uniform's value as last set: its components in order (a matrix column by column, as GL
/// stores it), as numbers.
pub type UniformValue = Vec<f64>;

/// A program: its inputs by name, and its uniforms' values.
#[derive(Debug, Clone, Default)]
pub struct Program {
    /// Attribute name to location, as glGetAttribLocation answered or glBindAttribLocation set.
    attributes: HashMap<String, u32>,
    /// Uniform location to name, as glGetUniformLocation answered.
    uniform_names: HashMap<i32, String>,
    /// Uniform values by name (GL resets them to zero when the program links again).
    values: HashMap<String, UniformValue>,
}

impl Program {
    pub fn attribute_located(&mut self, name: &[u8], location: i64) {
        if location >= 0 {
            self.attributes.insert(String::from_utf8_lossy(name).into_owned(), location as u32);
        }
    }

    pub fn uniform_located(&mut self, name: &[u8], location: i64) {
        if location >= 0 {
            // `name[0]` and `name` are the same location (GL allows both for arrays).
            let name = String::from_utf8_lossy(name);
            let name = name.strip_suffix("[0]").unwrap_or(&name);
            self.uniform_names.insert(location as i32, name.to_string());
        }
    }

    /// A link: uniforms go back to zero (their locations may change: they are asked again).
    pub fn linked(&mut self) {
        self.values.clear();
        self.uniform_names.clear();
    }

    /// glUniform*: the value at `location` (-1, or a location never asked for, is ignored).
    pub fn set_uniform(&mut self, location: i32, value: UniformValue) {
        if let Some(name) = self.uniform_names.get(&location) {
            self.values.insert(name.clone(), value);
        }
    }

    /// The location of attribute `name`, if the program asked for it.
    pub fn attribute(&self, name: &str) -> Option<u32> {
        self.attributes.get(name).copied()
    }

    /// Whether the program has a uniform `name` (asked for its location).
    pub fn has_uniform(&self, name: &str) -> bool {
        self.uniform_names.values().any(|n| n == name)
    }

    /// The value of uniform `name`, if it was set.
    pub fn uniform(&self, name: &str) -> Option<&[f64]> {
        self.values.get(name).map(|v| &v[..])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniforms_are_kept_by_name_until_the_program_links_again() {
        let mut p = Program::default();
        p.uniform_located(b"lightColor[0]", 4);
        p.uniform_located(b"MCVCMatrix", 7);
        p.uniform_located(b"missing", -1);
        p.set_uniform(4, vec![1.0, 0.5, 0.25]);
        p.set_uniform(9, vec![3.0]);
        assert_eq!(p.uniform("lightColor"), Some(&[1.0, 0.5, 0.25][..]));
        assert!(p.has_uniform("MCVCMatrix") && !p.has_uniform("missing"));
        p.linked();
        assert_eq!(p.uniform("lightColor"), None);
        p.attribute_located(b"vertexMC", 0);
        p.attribute_located(b"gone", -1);
        assert_eq!((p.attribute("vertexMC"), p.attribute("gone")), (Some(0), None));
    }
}
