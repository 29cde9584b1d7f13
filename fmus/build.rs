//! The FMU library finds the shared libraries an `.fmu` ships next to it
//! (`binaries/linux64/`: libmujoco when built with the MuJoCo backend), wherever the
//! host unpacks the archive.

fn main() {
    println!("cargo:rustc-cdylib-link-arg=-Wl,-rpath,$ORIGIN");
}
