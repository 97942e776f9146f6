//! The SPU instruction set: the instruction table, encoding and decoding, disassembly,
//! the bit-exact semantics, the simulated SPU core and its timing model.
//!
//! [`table`] is the single declaration every other module derives from.

#![warn(missing_docs)]

pub mod analysis;
pub mod codec;
pub mod disasm;
pub mod ext;
pub mod float;
pub mod jit;
pub mod machine;
pub mod profile;
pub mod stall;
pub mod static_timing;
pub mod table;
pub mod timing;

pub use codec::{decode, decode_ext, encode, operand_values, Inst};
pub use ext::{Extension, Extensions};
pub use table::{FormInfo, Format, Op, OperandKind, Pipe, Unit, Visitor, FORMS, OP_INFO};
