//! MCAP, the ROS 2 default storage since Iron: a small record-level reader and writer of our
//! own (not the `mcap` crate), because a recording cut short must still read, with exact
//! accounting of what was lost.
//!
//! * [`record`]: op codes, the bounds-checked cursor, one type per record.
//! * [`read`]: [`McapReader`] — summary when intact, a walk of the data section always;
//!   chunks `none`/`lz4`/`zstd` read in parallel as [`crate::source::Source`] parts.
//! * [`write`]: [`McapWriter`] — chunked files with message indexes, summary and CRCs.

pub(crate) mod read;
pub(crate) mod record;
pub(crate) mod write;

pub use read::McapReader;
pub use record::MAGIC;
pub use write::{ChunkCompression, McapWriter};
