//! `loam fmu`: a case packaged as an FMI 3.0 co-simulation FMU.
//!
//! An FMU is a ZIP archive (FMI 3.0, section 2.5 "FMU Distribution") holding
//!
//! ```text
//! modelDescription.xml                    generated here from the case's fmu section
//! binaries/<platform>/<id>.so             the loam-fmu shared library (the same for every case)
//! resources/loam_fmu.json                 manifest: the case file name, the instantiation token
//! resources/<case>.json                   the case (Gmsh paths rewritten into resources/)
//! resources/<kind>_<k>_<file>.msh         the Gmsh files it reads (kind: mesh, grid, body)
//! ```
//!
//! The key decision: the variable set is *per case*, so the model description is written
//! here and the shared library is generic; both take the variable table from
//! [`fmu_variables`], so value references agree by construction. The library finds its
//! case through the `resourcePath` of `fmi3InstantiateCoSimulation` and checks the
//! instantiation token against the manifest.

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::case::{Case, CaseError, MeshSpec};
use crate::simulation::Simulation;

/// File name of the manifest under `resources/`.
pub const MANIFEST: &str = "loam_fmu.json";

/// What the shared library reads from `resources/` at instantiation.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FmuManifest {
    /// Case file name under `resources/`.
    pub case: String,
    /// The `instantiationToken` of the model description.
    pub instantiation_token: String,
}

/// FMI causality of a variable (FMI 3.0 section 2.4.7.4 "Variable Attributes").
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Causality {
    /// The independent variable `time`.
    Independent,
    /// Set by the importer: a [`crate::case::FmuInputSpec`].
    Input,
    /// Read by the importer: a monitor.
    Output,
}

impl Causality {
    fn name(self) -> &'static str {
        match self {
            Causality::Independent => "independent",
            Causality::Input => "input",
            Causality::Output => "output",
        }
    }
}

/// One `Float64` variable of the FMU.
#[derive(Debug, Clone, PartialEq)]
pub struct FmuVariable {
    /// Variable name.
    pub name: String,
    /// Value reference.
    pub value_reference: u32,
    /// Causality.
    pub causality: Causality,
    /// Index into [`Simulation::inputs`] (inputs) or [`Simulation::outputs`] (outputs).
    pub index: usize,
    /// Unit (empty for none).
    pub unit: String,
    /// Start value (inputs only).
    pub start: Option<f64>,
    /// Description.
    pub description: String,
}

/// The FMU's variables: value reference 0 is `time`, then the inputs (1, 2, …) and the
/// outputs, in declaration order.
pub fn fmu_variables(sim: &Simulation) -> Vec<FmuVariable> {
    let mut v = vec![FmuVariable {
        name: "time".into(),
        value_reference: 0,
        causality: Causality::Independent,
        index: 0,
        unit: "s".into(),
        start: None,
        description: "Simulation time".into(),
    }];
    for (k, i) in sim.inputs.iter().enumerate() {
        v.push(FmuVariable {
            name: i.name.clone(),
            value_reference: v.len() as u32,
            causality: Causality::Input,
            index: k,
            unit: i.unit.clone(),
            start: Some(i.start),
            description: i.description.clone(),
        });
    }
    for (k, o) in sim.outputs.iter().enumerate() {
        v.push(FmuVariable {
            name: o.name.clone(),
            value_reference: v.len() as u32,
            causality: Causality::Output,
            index: k,
            unit: o.unit.clone(),
            start: None,
            description: o.description.clone(),
        });
    }
    v
}

/// SI base-unit exponents (kg, m, s) of the units Loam writes; other units are declared
/// by name only.
fn base_unit(unit: &str) -> Option<[i32; 3]> {
    Some(match unit {
        "1" => [0, 0, 0],
        "s" => [0, 0, 1],
        "m" => [0, 1, 0],
        "m/s" => [0, 1, -1],
        "m/s2" => [0, 1, -2],
        "N" => [1, 1, -2],
        "N/m" => [1, 0, -2],
        "Pa" => [1, -1, -2],
        "J" => [1, 2, -2],
        "kg" => [1, 0, 0],
        "m3" => [0, 3, 0],
        _ => return None,
    })
}

/// `&`, `<`, `>`, `"` and control characters escaped for an XML attribute.
fn xml_escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\n' => out.push_str("&#10;"),
            c if c.is_control() => {}
            c => out.push(c),
        }
    }
    out
}

/// A C identifier from the case name: `loam_<name>` with other characters as `_`.
pub fn model_identifier(case_name: &str) -> String {
    let body: String = case_name.chars().map(|c| if c.is_ascii_alphanumeric() { c } else { '_' }).collect();
    format!("loam_{body}")
}

/// FNV-1a 64-bit hash.
fn fnv1a(bytes: &[u8], seed: u64) -> u64 {
    bytes.iter().fold(seed, |h, &b| (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3))
}

/// A token in GUID form derived from the packaged case text and the variable table, so
/// that a library never runs a case it was not described with.
pub fn instantiation_token(case_text: &str, variables: &[FmuVariable]) -> String {
    let mut names = String::new();
    for v in variables {
        let _ = write!(names, "{}:{}:{};", v.value_reference, v.causality.name(), v.name);
    }
    let a = fnv1a(case_text.as_bytes(), 0xcbf2_9ce4_8422_2325);
    let b = fnv1a(names.as_bytes(), a ^ 0x9e37_79b9_7f4a_7c15);
    format!(
        "{{{:08x}-{:04x}-{:04x}-{:04x}-{:012x}}}",
        a >> 32,
        (a >> 16) & 0xffff,
        a & 0xffff,
        b >> 48,
        b & 0xffff_ffff_ffff
    )
}

/// The `modelDescription.xml` of a case (FMI 3.0 section 2.4 "FMI Description Schema"):
/// a co-simulation interface, the units, the `DefaultExperiment` from the case's time
/// stepping, the variables of [`fmu_variables`] and the `ModelStructure` listing every
/// output (as `Output` and `InitialUnknown`).
pub fn model_description(sim: &Simulation, identifier: &str, token: &str) -> String {
    let vars = fmu_variables(sim);
    let mut x = String::new();
    let description = sim.case.description.lines().next().unwrap_or("");
    let _ = writeln!(x, r#"<?xml version="1.0" encoding="UTF-8"?>"#);
    let _ = writeln!(
        x,
        r#"<fmiModelDescription fmiVersion="3.0" modelName="{}" description="{}" generationTool="Loam {}" instantiationToken="{}" variableNamingConvention="flat">"#,
        xml_escape(&sim.case.name),
        xml_escape(description),
        env!("CARGO_PKG_VERSION"),
        token
    );
    let _ = writeln!(
        x,
        r#"  <CoSimulation modelIdentifier="{identifier}" canHandleVariableCommunicationStepSize="true" canGetAndSetFMUState="false" canSerializeFMUState="false" fixedInternalStepSize="{}"/>"#,
        sim.case.analysis.time_step
    );
    let mut units: Vec<&str> = vars.iter().map(|v| v.unit.as_str()).filter(|u| !u.is_empty()).collect();
    units.sort_unstable();
    units.dedup();
    let _ = writeln!(x, "  <UnitDefinitions>");
    for u in &units {
        match base_unit(u) {
            Some([kg, m, s]) => {
                let mut attrs = String::new();
                for (name, e) in [("kg", kg), ("m", m), ("s", s)] {
                    if e != 0 {
                        let _ = write!(attrs, r#" {name}="{e}""#);
                    }
                }
                let _ = writeln!(x, r#"    <Unit name="{}"><BaseUnit{attrs}/></Unit>"#, xml_escape(u));
            }
            None => {
                let _ = writeln!(x, r#"    <Unit name="{}"/>"#, xml_escape(u));
            }
        }
    }
    let _ = writeln!(x, "  </UnitDefinitions>");
    let _ = writeln!(x, "  <LogCategories>");
    let _ = writeln!(x, r#"    <Category name="logStatusError" description="Errors: bad calls, bad input values"/>"#);
    let _ = writeln!(x, r#"    <Category name="logStatusDiscard" description="Steps that did not converge"/>"#);
    let _ = writeln!(x, r#"    <Category name="logInfo" description="Steps taken, Newton iterations"/>"#);
    let _ = writeln!(x, "  </LogCategories>");
    let _ = writeln!(
        x,
        r#"  <DefaultExperiment startTime="0" stopTime="{}" stepSize="{}"/>"#,
        sim.case.analysis.end_time, sim.case.analysis.time_step
    );
    let _ = writeln!(x, "  <ModelVariables>");
    for v in &vars {
        let mut attrs = format!(
            r#"name="{}" valueReference="{}" causality="{}" variability="continuous""#,
            xml_escape(&v.name),
            v.value_reference,
            v.causality.name()
        );
        if !v.description.is_empty() {
            let _ = write!(attrs, r#" description="{}""#, xml_escape(&v.description));
        }
        if !v.unit.is_empty() {
            let _ = write!(attrs, r#" unit="{}""#, xml_escape(&v.unit));
        }
        if let Some(s) = v.start {
            let _ = write!(attrs, r#" start="{s:?}""#);
        }
        let _ = writeln!(x, "    <Float64 {attrs}/>");
    }
    let _ = writeln!(x, "  </ModelVariables>");
    let _ = writeln!(x, "  <ModelStructure>");
    for v in vars.iter().filter(|v| v.causality == Causality::Output) {
        let _ = writeln!(x, r#"    <Output valueReference="{}"/>"#, v.value_reference);
    }
    for v in vars.iter().filter(|v| v.causality == Causality::Output) {
        let _ = writeln!(x, r#"    <InitialUnknown valueReference="{}"/>"#, v.value_reference);
    }
    let _ = writeln!(x, "  </ModelStructure>");
    x.push_str("</fmiModelDescription>\n");
    x
}

/// Why `loam fmu` failed.
#[derive(Debug, thiserror::Error)]
pub enum PackageError {
    /// The case does not load or build (exit code 2).
    #[error("{0}")]
    Case(#[from] CaseError),
    /// The loam-fmu shared library is not where it was looked for.
    #[error(
        "FMU library {} not found: build it with `cargo build --release --workspace` (or pass --library)",
        .0.display()
    )]
    MissingLibrary(PathBuf),
    /// Reading an input file or writing the FMU failed.
    #[error("{path}: {source}")]
    Io {
        /// The file concerned.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> PackageError + '_ {
    move |source| PackageError::Io { path: path.to_path_buf(), source }
}

/// `binaries/` folder name of this platform (FMI 3.0 section 2.5.1.4 "Platform Tuple").
pub fn platform_tuple() -> &'static str {
    match (std::env::consts::ARCH, std::env::consts::OS) {
        ("x86_64", "linux") => "x86_64-linux",
        ("aarch64", "linux") => "aarch64-linux",
        ("x86_64", "macos") => "x86_64-darwin",
        ("aarch64", "macos") => "aarch64-darwin",
        ("x86_64", "windows") => "x86_64-windows",
        ("aarch64", "windows") => "aarch64-windows",
        _ => "unknown",
    }
}

/// File name of the loam-fmu library on this platform (`libloam_fmu.so` on Linux).
pub fn library_file_name() -> String {
    format!("{}loam_fmu{}", std::env::consts::DLL_PREFIX, std::env::consts::DLL_SUFFIX)
}

/// The default place of the library: next to the running `loam` executable.
pub fn default_library_path() -> PathBuf {
    let dir = std::env::current_exe().ok().and_then(|p| p.parent().map(Path::to_path_buf)).unwrap_or_default();
    dir.join(library_file_name())
}

/// What [`package`] wrote.
#[derive(Debug, Clone, PartialEq)]
pub struct PackageSummary {
    /// `modelIdentifier`.
    pub model_identifier: String,
    /// Input names.
    pub inputs: Vec<String>,
    /// Output names.
    pub outputs: Vec<String>,
    /// Files in the archive.
    pub files: usize,
}

/// Packages `case_path` as an FMU at `out`, with the shared library at `library`.
pub fn package(case_path: &Path, out: &Path, library: &Path) -> Result<PackageSummary, PackageError> {
    let sim = Simulation::from_file(case_path)?;
    if !library.is_file() {
        return Err(PackageError::MissingLibrary(library.to_path_buf()));
    }
    let text = std::fs::read_to_string(case_path).map_err(io(case_path))?;
    // Gmsh files go under resources/ with new names; the packaged case refers to them there
    let mut json: serde_json::Value = serde_json::from_str(&text)
        .map_err(|e| CaseError::new(case_path.display().to_string(), format!("cannot re-read case: {e}")))?;
    let mut files: Vec<(String, Vec<u8>)> = Vec::new();
    for (k, d) in sim.case.domains.iter().enumerate() {
        // an FEM mesh, a background grid and a body mesh may each be a Gmsh file
        let body_mesh = match &d.material_points {
            Some(crate::case::BodySpec::Cells { mesh, .. }) => Some(mesh),
            _ => None,
        };
        let meshes = [
            (d.mesh.as_ref(), vec!["mesh"], "mesh"),
            (d.grid_mesh.as_ref(), vec!["grid_mesh"], "grid"),
            (body_mesh, vec!["material_points", "cells", "mesh"], "body"),
        ];
        for (spec, json_path, kind) in meshes {
            let Some(MeshSpec::Gmsh(file)) = spec else { continue };
            let src = sim.case.directory.join(file);
            let stem = file.file_name().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "mesh.msh".into());
            let packaged = format!("{kind}_{k}_{stem}");
            files.push((format!("resources/{packaged}"), std::fs::read(&src).map_err(io(&src))?));
            let mut node = &mut json["domains"][k];
            for key in json_path {
                node = &mut node[key];
            }
            node["gmsh"] = serde_json::Value::String(packaged);
        }
    }
    let case_file = format!("{}.json", sim.case.name);
    let case_text = serde_json::to_string_pretty(&json).expect("JSON values serialise");
    // the packaged case must build exactly as the original
    Case::parse(&case_text)?;
    let vars = fmu_variables(&sim);
    let token = instantiation_token(&case_text, &vars);
    let identifier = model_identifier(&sim.case.name);
    let manifest = FmuManifest { case: case_file.clone(), instantiation_token: token.clone() };
    files.insert(0, ("modelDescription.xml".into(), model_description(&sim, &identifier, &token).into_bytes()));
    files.push((
        format!("binaries/{}/{identifier}{}", platform_tuple(), std::env::consts::DLL_SUFFIX),
        std::fs::read(library).map_err(io(library))?,
    ));
    files.push((format!("resources/{case_file}"), case_text.into_bytes()));
    files.push((
        format!("resources/{MANIFEST}"),
        serde_json::to_string_pretty(&manifest).expect("manifest serialises").into_bytes(),
    ));
    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(io(dir))?;
    }
    let archive = zip(&files).map_err(io(out))?;
    std::fs::write(out, archive).map_err(io(out))?;
    Ok(PackageSummary {
        model_identifier: identifier,
        inputs: sim.inputs.iter().map(|i| i.name.clone()).collect(),
        outputs: sim.outputs.iter().map(|o| o.name.clone()).collect(),
        files: files.len(),
    })
}

/// A ZIP archive (deflate) of `(path, contents)` entries, files readable by all
/// (`rw-r--r--`), as FMI 3.0 section 2.5 asks.
fn zip(files: &[(String, Vec<u8>)]) -> std::io::Result<Vec<u8>> {
    use zip::write::SimpleFileOptions;
    let mut archive = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let options =
        SimpleFileOptions::default().compression_method(zip::CompressionMethod::Deflated).unix_permissions(0o644);
    for (name, data) in files {
        archive.start_file(name.as_str(), options).map_err(std::io::Error::other)?;
        archive.write_all(data)?;
    }
    Ok(archive.finish().map_err(std::io::Error::other)?.into_inner())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identifiers_tokens_and_escapes() {
        assert_eq!(model_identifier("footing-fmu.v2"), "loam_footing_fmu_v2");
        assert_eq!(xml_escape(r#"a<b & "c""#), "a&lt;b &amp; &quot;c&quot;");
        let t = instantiation_token("{}", &[]);
        assert_eq!(t.len(), 38);
        assert_ne!(t, instantiation_token("{ }", &[]));
    }

    #[test]
    fn zip_entries_read_back() {
        use std::io::Read;
        let files = [
            ("modelDescription.xml".to_string(), b"hello hello hello".to_vec()),
            ("resources/a.json".into(), b"{}".to_vec()),
        ];
        let z = zip(&files).unwrap();
        let mut archive = zip::ZipArchive::new(std::io::Cursor::new(z)).unwrap();
        assert_eq!(archive.len(), 2);
        for (name, data) in &files {
            let mut f = archive.by_name(name).unwrap();
            assert_eq!(f.compression(), zip::CompressionMethod::Deflated);
            assert_eq!(f.unix_mode().map(|m| m & 0o777), Some(0o644));
            let mut back = Vec::new();
            f.read_to_end(&mut back).unwrap();
            assert_eq!(&back, data);
        }
    }
}
