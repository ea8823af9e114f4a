//! Files: BCC yarn curves (read/write, [W19 §5]'s format, DESIGN §2.6), MADYPG `.pyp`
//! periodic yarn patterns (read), and two writers for inspection and external reference
//! renders: Mitsuba 3 curve text and OBJ `l` polylines. Every file is written through
//! `btf_core::fs::write_atomic_with` (temporary name, checked writes, fsync, rename), so a
//! failed write leaves the previous file untouched.

pub mod bcc;
pub mod pyp;
pub mod text;

pub use bcc::{BccFile, parse_bcc, read_bcc, write_bcc};
pub use pyp::{PypPattern, parse_pyp, read_pyp};
pub use text::{write_mitsuba_fibers, write_mitsuba_yarns, write_obj_fibers, write_obj_yarns};
