//! Bit-exact SPU floating point (under construction).
