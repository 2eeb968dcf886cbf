//! What a frame is coloured by: a point or cell field, reduced to one number per point or
//! cell, with its unit.
//!
//! `NAME` for a scalar; `NAME:x|y|z|magnitude` for a vector (default magnitude);
//! `NAME:xx|yy|zz|xy|yz|xz` (or `yx`, `zy`, `zx`) for a tensor stored row by row as 3×3.

use super::results::FieldData;

/// Which number of a field's entry is shown.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Component {
    /// A scalar field's value.
    Scalar,
    /// Component `i` of a vector.
    Vector(usize),
    /// Euclidean norm of a vector.
    Magnitude,
    /// Entry `(i, j)` of a tensor.
    Tensor(usize, usize),
}

/// A field and the component to show, as given on the command line (`cauchy_stress:yy`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FieldSelection {
    /// Field name.
    pub name: String,
    /// The component as written after `:` (`None`: a scalar, or a vector's magnitude).
    pub component: Option<String>,
}

impl FieldSelection {
    /// Parses `NAME` or `NAME:COMPONENT`.
    pub fn parse(text: &str) -> Self {
        match text.split_once(':') {
            Some((name, c)) => Self { name: name.to_string(), component: Some(c.to_string()) },
            None => Self { name: text.to_string(), component: None },
        }
    }

    /// The component of a field with `components` values per entry, or why it does not
    /// apply.
    pub fn component(&self, components: usize) -> Result<Component, String> {
        let axis = |c: char| "xyz".find(c);
        let kind = match components {
            1 => "a scalar",
            3 => "a vector (x|y|z|magnitude)",
            9 => "a tensor (xx|yy|zz|xy|yz|xz)",
            _ => "",
        };
        let wrong = |c: &str| format!("field `{}` is {kind}: no component `{c}`", self.name);
        match (components, self.component.as_deref()) {
            (1, None) => Ok(Component::Scalar),
            (3, None | Some("magnitude")) => Ok(Component::Magnitude),
            (3, Some(c)) if c.len() == 1 => {
                axis(c.chars().next().unwrap_or(' ')).map(Component::Vector).ok_or_else(|| wrong(c))
            }
            (9, None) => Err(format!("field `{}` is a tensor: give a component, e.g. `{}:yy`", self.name, self.name)),
            (9, Some(c)) if c.len() == 2 => {
                let mut ch = c.chars().map(axis);
                match (ch.next().flatten(), ch.next().flatten()) {
                    (Some(i), Some(j)) => Ok(Component::Tensor(i, j)),
                    _ => Err(wrong(c)),
                }
            }
            (1 | 3 | 9, Some(c)) => Err(wrong(c)),
            (n, _) => Err(format!(
                "field `{}` has {n} components per entry; only scalars, vectors and tensors are drawn",
                self.name
            )),
        }
    }

    /// The values of `field` reduced to this component, one per entry.
    pub fn values(&self, field: &FieldData) -> Result<Vec<f64>, String> {
        let c = self.component(field.components)?;
        let n = field.components;
        Ok(field
            .values
            .chunks_exact(n)
            .map(|v| match c {
                Component::Scalar => v[0],
                Component::Vector(i) => v[i],
                Component::Magnitude => v.iter().map(|x| x * x).sum::<f64>().sqrt(),
                Component::Tensor(i, j) => v[3 * i + j],
            })
            .collect())
    }

    /// The label of the colour bar: the name with spaces, and the component.
    pub fn label(&self) -> String {
        let name = self.name.replace('_', " ");
        match &self.component {
            Some(c) => format!("{name} {c}"),
            None => name,
        }
    }

    /// A file-name-safe form (`cauchy_stress_yy`).
    pub fn slug(&self) -> String {
        let text = match &self.component {
            Some(c) => format!("{}_{c}", self.name),
            None => self.name.clone(),
        };
        text.chars().map(|c| if c.is_ascii_alphanumeric() || c == '_' || c == '-' { c } else { '_' }).collect()
    }
}

/// SI unit of a field written by Loam, from its name (`""` where it has none, `"1"` for a
/// ratio; `None` where the name is not known).
pub fn unit(name: &str) -> Option<&'static str> {
    Some(match name {
        "displacement" | "displacement_increment" => "m",
        "velocity" => "m/s",
        "acceleration" => "m/s²",
        "mass" => "kg",
        "volume" => "m³",
        "force" => "N",
        "cauchy_stress" | "von_mises_stress" | "preconsolidation_pressure" | "pressure" => "Pa",
        "deformation_gradient" | "green_lagrange_strain" | "normal" => "1",
        "id" | "active" | "yield_flag" => "",
        n if n.ends_with("_stress") || n.ends_with("_pressure") => "Pa",
        n if n.contains("strain") => "1",
        _ => return None,
    })
}

/// How values are shown: divided by `factor` and labelled with `unit` (an SI prefix picked
/// from the range, `kPa` for stresses in the thousands of pascals).
#[derive(Debug, Clone, PartialEq)]
pub struct DisplayUnit {
    /// Values are divided by this.
    pub factor: f64,
    /// The unit with its prefix (`""` for none).
    pub unit: String,
}

impl DisplayUnit {
    /// The prefix for values up to `largest` in magnitude: k, M, G for large values of a
    /// unit that takes prefixes (Pa, N, J), none otherwise.
    pub fn for_range(unit: &str, largest: f64) -> Self {
        let prefixed = matches!(unit, "Pa" | "N" | "J");
        let (factor, prefix) = match largest {
            l if prefixed && l >= 1e9 => (1e9, "G"),
            l if prefixed && l >= 1e6 => (1e6, "M"),
            l if prefixed && l >= 1e3 => (1e3, "k"),
            _ => (1.0, ""),
        };
        Self { factor, unit: format!("{prefix}{unit}") }
    }

    /// `label (unit)`, or `label` for a field without a unit, `label (–)` for a ratio.
    pub fn label(&self, label: &str) -> String {
        match self.unit.as_str() {
            "" => label.to_string(),
            "1" => format!("{label} (–)"),
            u => format!("{label} ({u})"),
        }
    }
}

/// Axis tick label of `v` on an axis spanning `span`: round-off next to zero (`1e-17` on
/// an axis of metres) reads as 0.
pub fn axis_tick(v: f64, span: f64) -> String {
    tick(if v.abs() < 1e-9 * span.abs() { 0.0 } else { v })
}

/// Tick label of `v`: up to four significant digits, plain or scientific.
pub fn tick(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let a = v.abs();
    if !(1e-3..1e5).contains(&a) {
        let s = format!("{v:.2e}");
        return s.replace("e0", "").replace(".00e", "e");
    }
    let digits = (3 - a.log10().floor() as i32).clamp(0, 6) as usize;
    let s = format!("{v:.digits$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn field(components: usize, values: Vec<f64>) -> FieldData {
        FieldData { name: "f".into(), components, values }
    }

    #[test]
    fn components_of_scalars_vectors_and_tensors() {
        let v = field(3, vec![3.0, 4.0, 0.0, 1.0, 2.0, 2.0]);
        assert_eq!(FieldSelection::parse("f").values(&v).unwrap(), vec![5.0, 3.0]);
        assert_eq!(FieldSelection::parse("f:y").values(&v).unwrap(), vec![4.0, 2.0]);
        let t = field(9, (0..9).map(f64::from).collect());
        assert_eq!(FieldSelection::parse("f:xy").values(&t).unwrap(), vec![1.0]);
        assert_eq!(FieldSelection::parse("f:yx").values(&t).unwrap(), vec![3.0]);
        assert_eq!(FieldSelection::parse("f:zz").values(&t).unwrap(), vec![8.0]);
        assert!(FieldSelection::parse("f").values(&t).unwrap_err().contains("give a component"));
        assert!(FieldSelection::parse("f:w").values(&v).unwrap_err().contains("no component `w`"));
        assert!(FieldSelection::parse("f:x").values(&field(1, vec![1.0])).unwrap_err().contains("a scalar"));
    }

    #[test]
    fn units_prefixes_and_ticks() {
        assert_eq!(unit("cauchy_stress"), Some("Pa"));
        assert_eq!(unit("pressure"), Some("Pa"));
        assert_eq!(unit("accumulated_plastic_deviatoric_strain"), Some("1"));
        assert_eq!(unit("whatever"), None);
        let d = DisplayUnit::for_range("Pa", 2.5e4);
        assert_eq!((d.factor, d.unit.as_str()), (1e3, "kPa"));
        assert_eq!(d.label("stress yy"), "stress yy (kPa)");
        assert_eq!(DisplayUnit::for_range("1", 3.0).label("strain"), "strain (–)");
        assert_eq!(DisplayUnit::for_range("m", 3e4).unit, "m");
        assert_eq!(tick(0.25), "0.25");
        assert_eq!(tick(-1234.4), "-1234");
        assert_eq!(tick(2.0e-5), "2e-5");
        assert_eq!(tick(0.0), "0");
        assert_eq!(axis_tick(-1.39e-17, 0.3), "0");
        assert_eq!(FieldSelection::parse("cauchy_stress:yy").slug(), "cauchy_stress_yy");
    }
}
