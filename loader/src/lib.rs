//! The PPE host: scenes, BVH, staging and the SPE runtime (under construction).
