//! Packaging the FMU shared library into `.fmu` archives. The library describes
//! itself (`plamo_fmu_model_description`), so each archive's `modelDescription.xml`
//! is exactly what the binary implements.

use std::ffi::{CStr, c_char};
use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, anyhow, bail};

/// File name of the FMU shared library cargo builds (crate `plamo-fmu`).
pub const LIBRARY_FILE: &str = "libplamo_fmu.so";

/// One written archive.
#[derive(Debug, Clone, PartialEq)]
pub struct PackagedFmu {
    /// Where the `.fmu` was written.
    pub path: PathBuf,
    /// `modelName` of its description.
    pub model_name: String,
    /// `guid` of its description.
    pub guid: String,
}

/// Find the FMU library built alongside the running executable: binaries live in
/// `target/<profile>/`, tests in `target/<profile>/deps/`.
pub fn find_library() -> Result<PathBuf> {
    let exe = std::env::current_exe().context("locating the running executable")?;
    let mut dirs = Vec::new();
    if let Some(dir) = exe.parent() {
        dirs.push(dir.to_path_buf());
        if let Some(up) = dir.parent() {
            dirs.push(up.to_path_buf());
        }
    }
    dirs.iter()
        .map(|d| d.join(LIBRARY_FILE))
        .find(|p| p.is_file())
        .ok_or_else(|| {
            anyhow!(
                "{LIBRARY_FILE} not found next to {} (looked in {}); build it with `cargo build --release -p plamo-fmu` (or `cargo build -p plamo-fmu` for a debug plamo)",
                exe.display(),
                dirs.iter().map(|d| d.display().to_string()).collect::<Vec<_>>().join(", ")
            )
        })
}

/// The model descriptions the library reports, in order.
pub fn model_descriptions(library: &Path) -> Result<Vec<String>> {
    // SAFETY: loading our own cdylib runs no user initialisers beyond Rust's std, and
    // the symbol has the signature declared in plamo-fmu's lib.rs.
    let lib = unsafe { libloading::Library::new(library) }
        .with_context(|| format!("loading {}", library.display()))?;
    // SAFETY: as above; the returned pointers are NUL-terminated strings owned by the
    // library, copied before it is unloaded.
    unsafe {
        let describe: libloading::Symbol<unsafe extern "C" fn(u32) -> *const c_char> =
            lib.get(b"plamo_fmu_model_description\0").with_context(|| {
                format!(
                    "{} has no plamo_fmu_model_description: not a plamo FMU library",
                    library.display()
                )
            })?;
        let mut out = Vec::new();
        for i in 0.. {
            let p = describe(i);
            if p.is_null() {
                break;
            }
            out.push(CStr::from_ptr(p).to_string_lossy().into_owned());
        }
        Ok(out)
    }
}

/// Shared libraries the FMU library links that a host machine lacks, to ship next to
/// it in `binaries/linux64/` (its rpath includes `$ORIGIN`): libmujoco when it was
/// built with the MuJoCo backend. Found by their soname in the library's dynamic
/// string table, in `third_party/mujoco/lib` where the build's rpath looks.
pub fn bundled_libraries(library: &Path, binary: &[u8]) -> Result<Vec<PathBuf>> {
    const PREFIX: &[u8] = b"libmujoco.so.";
    let mut sonames: Vec<String> = Vec::new();
    let mut from = 0;
    while let Some(i) = binary[from..]
        .windows(PREFIX.len())
        .position(|w| w == PREFIX)
        .map(|i| from + i)
    {
        from = i + PREFIX.len();
        // A soname entry: the prefix, a version of digits and dots, then NUL.
        let version: Vec<u8> = binary[from..]
            .iter()
            .copied()
            .take_while(|b| b.is_ascii_digit() || *b == b'.')
            .collect();
        let preceded_by_nul = i == 0 || binary[i - 1] == 0;
        if !version.is_empty() && preceded_by_nul && binary.get(from + version.len()) == Some(&0) {
            let name = format!("libmujoco.so.{}", String::from_utf8_lossy(&version));
            if !sonames.contains(&name) {
                sonames.push(name);
            }
        }
    }
    let dir = library.parent().unwrap_or(Path::new("."));
    sonames
        .iter()
        .map(|name| {
            ["../third_party/mujoco/lib", "../../third_party/mujoco/lib", "../../../third_party/mujoco/lib"]
                .iter()
                .map(|up| dir.join(up).join(name))
                .find(|p| p.is_file())
                .ok_or_else(|| {
                    anyhow!(
                        "{} was built with the MuJoCo backend and needs {name}, which is not in third_party/mujoco/lib: run scripts/install-mujoco.sh",
                        library.display()
                    )
                })
        })
        .collect()
}

fn attribute(xml: &str, name: &str) -> Result<String> {
    let key = format!(" {name}=\"");
    let start = xml
        .find(&key)
        .ok_or_else(|| anyhow!("model description has no {name}"))?
        + key.len();
    let end = xml[start..]
        .find('"')
        .ok_or_else(|| anyhow!("unterminated {name}"))?;
    Ok(xml[start..start + end].to_string())
}

/// Write one `.fmu` per model the library serves into `out_dir`, shipping the given
/// files (e.g. scene TOML files) under `resources/`.
pub fn package_all(
    library: &Path,
    out_dir: &Path,
    resources: &[PathBuf],
) -> Result<Vec<PackagedFmu>> {
    let descriptions = model_descriptions(library)?;
    if descriptions.is_empty() {
        bail!("{} describes no model", library.display());
    }
    let binary =
        std::fs::read(library).with_context(|| format!("reading {}", library.display()))?;
    let bundled = bundled_libraries(library, &binary)?;
    std::fs::create_dir_all(out_dir).with_context(|| format!("creating {}", out_dir.display()))?;
    let mut written = Vec::new();
    for xml in descriptions {
        let model_name = attribute(&xml, "modelName")?;
        let identifier = attribute(&xml, "modelIdentifier")?;
        let guid = attribute(&xml, "guid")?;
        let path = out_dir.join(format!("{model_name}.fmu"));
        let file = File::create(&path).with_context(|| format!("creating {}", path.display()))?;
        let mut zip = zip::ZipWriter::new(file);
        let opts = zip::write::SimpleFileOptions::default()
            .compression_method(zip::CompressionMethod::Deflated);
        zip.start_file("modelDescription.xml", opts)?;
        zip.write_all(xml.as_bytes())?;
        zip.start_file(format!("binaries/linux64/{identifier}.so"), opts)?;
        zip.write_all(&binary)?;
        for b in &bundled {
            let name = b.file_name().unwrap_or_default().to_string_lossy();
            zip.start_file(format!("binaries/linux64/{name}"), opts)?;
            zip.write_all(&std::fs::read(b).with_context(|| format!("reading {}", b.display()))?)?;
        }
        for r in resources {
            let name = r
                .file_name()
                .ok_or_else(|| anyhow!("resource {} has no file name", r.display()))?;
            zip.start_file(format!("resources/{}", name.to_string_lossy()), opts)?;
            zip.write_all(
                &std::fs::read(r).with_context(|| format!("reading resource {}", r.display()))?,
            )?;
        }
        zip.finish()?;
        written.push(PackagedFmu {
            path,
            model_name,
            guid,
        });
    }
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ships_libmujoco_only_when_the_library_names_it_as_a_soname() {
        let root = std::env::temp_dir().join(format!("plamo-bundle-{}", std::process::id()));
        let lib = root.join("target/debug/libplamo_fmu.so");
        std::fs::create_dir_all(lib.parent().unwrap()).unwrap();
        // No soname: nothing to ship, even with a message that mentions the library.
        let plain = b"\0libc.so.6\0libmujoco.so.3.17.0 is missing\0".to_vec();
        assert!(bundled_libraries(&lib, &plain).unwrap().is_empty());
        // A soname the build's third_party/ lacks: a clear error.
        let linked = b"\0libm.so.6\0libmujoco.so.3.17.0\0libc.so.6\0".to_vec();
        let e = bundled_libraries(&lib, &linked).unwrap_err().to_string();
        assert!(
            e.contains("libmujoco.so.3.17.0") && e.contains("install-mujoco.sh"),
            "{e}"
        );
        // Where the rpath looks: shipped.
        let mj = root.join("third_party/mujoco/lib/libmujoco.so.3.17.0");
        std::fs::create_dir_all(mj.parent().unwrap()).unwrap();
        std::fs::write(&mj, b"elf").unwrap();
        let found = bundled_libraries(&lib, &linked).unwrap();
        assert_eq!(found.len(), 1);
        assert!(found[0].ends_with("libmujoco.so.3.17.0") && found[0].is_file());
        let _ = std::fs::remove_dir_all(&root);
    }
}
