//! placeholder

use std::path::Path;

/// Opens.
pub fn open(path: &Path) -> Result<crate::decoded::DecodedSource, crate::error::Error> {
    Err(crate::error::Error::NotABag {
        path: path.to_path_buf(),
        what: "todo".into(),
    })
}
