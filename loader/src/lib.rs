//! The PPE host side of the ray tracer: everything the SPU kernels need prepared in main
//! memory before a frame starts, and the plain-Rust reference they are checked against.
//!
//! - [`scene`], [`obj`], [`ply`]: triangle scenes loaded from files (optionally gzip'd).
//! - [`procedural`]: deterministic built-in stand-ins for the paper's ERW6, Conference and
//!   VW Beetle scenes, so everything works where the shared scene files are absent.
//! - [`camera`]: the pinhole camera and the exact primary-ray convention the kernels share.
//! - [`animation`], [`refit`]: moving scenes (built-in animations, OBJ keyframes) and the
//!   per-frame BVH refit with its rebuild policy; [`spu_refit`], the same refit on the SPEs;
//!   [`animate`], an animation's frames: refit, render, validate.
//! - [`bvh`]: the binned-SAH bounding volume hierarchy (paper section 3.2).
//! - [`layout`]: the big-endian DMA records (32-byte nodes, 64-byte triangle and vertex
//!   records, paper section 5.1) and the staged main-memory image.
//! - [`shading`]: the shading model (diffuse, interpolated normals, point lights, shadows)
//!   the shading kernels and the reference share, and the `--shade` modes.
//! - [`reference`](mod@reference): a scalar ray caster over the same records that defines the expected
//!   kernel output.
//! - [`reflection`]: reflection rays (`--shade reflect`): the model, the reference's frame
//!   with its hits per bounce, and the reflection packets' coherence.
//! - [`stats`]: a frame's statistics as typed JSON (`spu render --stats`).
//! - [`timeline`]: when each tile and packet was traced, from the SPUs' event logs.
//! - [`render`]: the one render API (configuration, prepared scene, frame, validation)
//!   over [`runtime`], the frame programs ([`variants`], [`kernels`]) and [`frame`]'s layout.
//! - [`ppe`]: the SPU runtime `spu as --runtime` links with a program.
//!
//! The SPUs, their main memory, quanta and host threads are the SPE runtime's
//! ([`spu_spe::System`]); [`runtime`] runs a frame's SPUs on it.

pub mod animate;
pub mod animation;
pub mod bvh;
pub mod camera;
pub mod error;
pub mod layout;
pub mod obj;
pub mod ply;
pub mod procedural;
pub mod reference;
pub mod refit;
pub mod reflection;
pub mod scene;
pub mod shading;

pub use bvh::{Bvh, BvhConfig, BvhNode};
pub use camera::{Camera, CameraBasis};
pub use error::LoadError;
pub use layout::StagedScene;
pub use scene::{Material, Scene, Triangle};
pub mod frame;
pub mod kernel_abi;
pub mod kernel_image;
pub mod kernels;
pub mod membench;
pub mod ppe;
pub mod render;
pub mod runtime;
pub mod spu_refit;
pub mod stats;
pub mod timeline;
pub mod variants;
