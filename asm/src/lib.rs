//! GNU `as` compatible assembler for SPU (under construction).
