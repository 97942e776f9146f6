//! The simulated SPU core (under construction).
