//! The SPU runtime `spu as --runtime` links with a program ([`runtime`]). The PPE side of a
//! run (start state, PPE-assisted calls) is the SPE runtime's: [`spu_spe::ppe`].

pub mod runtime;
