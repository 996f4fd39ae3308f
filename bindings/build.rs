//! Gives the Python module the same run-time path to libsumo as the core's binary: the core's
//! build script found SUMO (`$SUMO_HOME`, else Debian's system paths) and, for a SUMO outside the
//! system paths, passes its library directory on as `DEP_SUMOCPP_LIB_DIR`. A run-time path set by
//! a dependency's build script reaches only that package's own targets, so this cdylib sets its own.
fn main() {
    println!("cargo:rerun-if-env-changed=DEP_SUMOCPP_LIB_DIR");
    if let Ok(lib) = std::env::var("DEP_SUMOCPP_LIB_DIR") {
        println!("cargo:rustc-link-arg-cdylib=-Wl,-rpath,{lib}");
    }
}
