//! The SPE runtime, shaped like libspe2: a [`System`] of SPU contexts sharing a main
//! memory, run together quantum by quantum on host threads, with the host's side of every
//! channel and stop. `spu run`, `spu prof` and the ray tracer's host are built on it; a
//! Rust program embeds the simulator through it as a C program used libspe2.
//!
//! | libspe2 | here |
//! |---|---|
//! | `spe_context_create` | [`System::create_context`] with a [`ContextConfig`] (engine, timing) |
//! | `spe_image_open`, `spe_program_load` | [`System::load_elf`], [`System::load_elf_file`], [`System::load`] of a [`Program`] |
//! | `spe_context_run` | [`System::run`]: every context at once, to a stop or a wait |
//! | `spe_in_mbox_write`, `spe_out_mbox_read`, `spe_out_intr_mbox_read` | [`System::write_in_mbox`], [`System::read_out_mbox`], [`System::read_out_intr_mbox`] |
//! | `spe_signal_write` | [`System::write_signal`] with a [`Signal`] |
//! | `spe_ls_area_get` | [`System::ls`] |
//! | `spe_callback_handler_register` | [`System::register_stop_handler`], [`System::register_call_handler`] |
//! | the default C99 and POSIX.1 handlers | served unless replaced, in the sandbox [`System::set_root`] grants |
//!
//! **Loading** checks the program first ([`Program`]): segments outside local store or
//! overlapping, empty files and text files are refused with a [`LoadError`]. The entry
//! state is the SDK loader's ([`ppe::start`]): the stack at the top of local store and
//! `main(argc, argv)` ([`Start::Shell`]) or `main(speid, argp, envp)` ([`Start::Api`]).
//!
//! **Running** returns an [`Outcome`]. A context that reads an empty inbound mailbox or
//! signal register (or writes a full outbound mailbox) *waits*: when every running context
//! waits, the run comes back [`Outcome::Waiting`] naming each one's [`Channel`]; the host
//! serves it and runs again. Only when the host served nothing in between is it an
//! [`Outcome::Deadlock`]. A stop with a registered handler runs the handler, between
//! quanta, in context order; PPE-assisted calls (stop 0x2100..0x21ff) are served the same
//! way. Contexts see each other's main-memory writes and signals at quantum ends
//! ([`Quantum`]), so the results are the same for any number of host threads
//! ([`System::set_threads`]) and either engine.
//!
//! # Example: two SPUs, a mailbox and a signal
//!
//! SPU 0 reads a word from its inbound mailbox, adds one, keeps it in local store and
//! sends it out through its outbound mailbox; the host passes it on to SPU 1's first
//! signal-notification register; SPU 1 doubles it, keeps it and mails it back.
//!
//! ```
//! use spu_spe::{Channel, ContextConfig, Outcome, Signal, Start, State, System, Wait};
//! use spu_isa::machine::StopReason;
//!
//! let first = "_start: rdch $3, $SPU_RdInMbox\n ai $3, $3, 1\n stqa $3, 0x1000\n \
//!              wrch $SPU_WrOutMbox, $3\n stop 0x2000\n";
//! let second = "_start: rdch $4, $SPU_RdSigNotify1\n shli $4, $4, 1\n stqa $4, 0x1000\n \
//!               wrch $SPU_WrOutMbox, $4\n stop 0x2001\n";
//! let elf = |src: &str| spu_asm::assemble(src, "x.s", &Default::default()).unwrap().elf;
//!
//! let mut system = System::new(1 << 16);
//! let start = Start::Api { argp: 0, envp: 0 };
//! let a = system.create_context(ContextConfig::default());
//! let b = system.create_context(ContextConfig::default());
//! system.load_elf(a, &elf(first), &start).unwrap();
//! system.load_elf(b, &elf(second), &start).unwrap();
//!
//! // Both wait at their first instruction: SPU 0 on its mailbox, SPU 1 on a signal.
//! let waits = vec![
//!     Wait { context: a, channel: Channel::InMbox, pc: 0 },
//!     Wait { context: b, channel: Channel::Signal(Signal::One), pc: 0 },
//! ];
//! assert_eq!(system.run(1_000_000), Outcome::Waiting(waits.clone()));
//! // Running again with nothing served: nothing can make progress.
//! assert_eq!(system.run(1_000_000), Outcome::Deadlock(waits));
//!
//! assert!(system.write_in_mbox(a, 41));
//! let outcome = system.run(1_000_000);
//! assert_eq!(*system.state(a), State::Stopped(StopReason::Stop(0x2000)));
//! assert_eq!(
//!     outcome,
//!     Outcome::Waiting(vec![Wait { context: b, channel: Channel::Signal(Signal::One), pc: 0 }])
//! );
//! let word = system.read_out_mbox(a).unwrap();
//! assert_eq!(word, 42);
//! system.write_signal(b, Signal::One, word);
//! assert_eq!(system.run(1_000_000), Outcome::Stopped);
//! assert_eq!(*system.state(b), State::Stopped(StopReason::Stop(0x2001)));
//! assert_eq!(system.read_out_mbox(b), Some(84));
//!
//! // Each kept its word in the preferred slot of local store's quadword 0x1000.
//! assert_eq!(system.ls(a)[0x1000..0x1004], 42u32.to_be_bytes());
//! assert_eq!(system.ls(b)[0x1000..0x1004], 84u32.to_be_bytes());
//! ```
//!
//! # Example: a stop handler
//!
//! A user stop code resumes the program when a handler takes it, as libspe2's callbacks
//! did; here the handler answers in `$3`.
//!
//! ```
//! use spu_spe::{ContextConfig, Outcome, Resume, Start, State, System};
//! use spu_isa::machine::StopReason;
//!
//! let src = "_start: il $3, 20\n stop 0x1234\n ai $3, $3, 2\n stop 0x2000\n";
//! let elf = spu_asm::assemble(src, "x.s", &Default::default()).unwrap().elf;
//! let mut system = System::new(1 << 16);
//! let spu = system.create_context(ContextConfig::default());
//! system.load_elf(spu, &elf, &Start::Api { argp: 0, envp: 0 }).unwrap();
//! system.register_stop_handler(0x1234, |stopped| {
//!     let [x, ..] = stopped.spu.reg(3);
//!     stopped.spu.set_reg(3, [x * 2, 0, 0, 0]);
//!     Ok(Resume::Continue)
//! });
//! assert_eq!(system.run(1_000), Outcome::Stopped);
//! assert_eq!(*system.state(spu), State::Stopped(StopReason::Stop(0x2000)));
//! assert_eq!(system.spu(spu).reg(3)[0], 42);
//! ```

#![deny(missing_docs)]

mod channel;
pub mod elf;
mod gang;
pub mod ppe;
mod program;
mod system;

pub use channel::{Channel, Signal};
pub use ppe::start::Start;
pub use program::{looks_like_text, LoadError, Program, MAX_FILE_BYTES};
pub use system::{
    ContextConfig, ContextId, LibraryCall, Outcome, Quantum, Resume, State, Stopped, System, Wait,
};
