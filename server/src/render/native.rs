//! Native libraries loaded at run time (Open Image Denoise, Embree), as
//! OpenCL is: opening one by path, and resolving its entry points by name
//! into a table of function pointers ([`symbols`]).
#![allow(unsafe_code)]

use std::path::Path;

/// Opens the library at `path` (a file name alone searches the system's
/// library path), or says why it cannot.
pub fn open(path: &Path) -> Result<libloading::Library, String> {
    // SAFETY: loading runs the library's initialisers; those of the
    // libraries loaded here (OIDN, Embree and its TBB) only set up their
    // own state.
    unsafe { libloading::Library::new(path) }.map_err(|e| {
        // libloading's message is "dlopen failed"; the loader's own is its
        // source.
        let why = std::error::Error::source(&e).map_or_else(|| e.to_string(), |s| s.to_string());
        format!("cannot load {}: {why}", path.display())
    })
}

/// `$api { field: <entry point $name of $lib>, ... }`, returning from the
/// enclosing function with an error naming the first entry point missing
/// (and `$needed`, what to install) if the library lacks one.
macro_rules! symbols {
    ($api:ident, $lib:expr, $path:expr, $needed:literal, $($field:ident = $name:literal),* $(,)?) => {
        $api {
            $($field: {
                // SAFETY: the symbol is the library's C function of this
                // name, whose signature the field's type copies from its
                // header; the pointer is used only while the library value
                // kept beside the table keeps the library loaded.
                let s = unsafe { $lib.get(concat!($name, "\0").as_bytes()) }.map_err(|e| {
                    format!("{} lacks {}: {e} ({} is needed)", $path.display(), $name, $needed)
                })?;
                *s
            },)*
        }
    };
}
pub(crate) use symbols;
