//! The system object: SPU contexts, the main memory they share, the quantum policy and the
//! host threads that run them, with the host's side of every channel and stop. A run goes
//! quantum by quantum (`gang`); between quanta the host thread alone serves the stops
//! (handlers, PPE-assisted calls) in context order, so results never depend on threads.

use crate::channel::{Channel, Signal};
use crate::gang::{run_quanta, Next};
use crate::ppe::start::{self, Entry, Start};
use crate::ppe::{Host, CALL_STOPS};
use crate::program::{LoadError, Program};
use spu_isa::jit::{CodeCache, Engine};
use spu_isa::machine::{apply_quantum, MainMemory, Spu, StopReason};
use spu_isa::timing::TimingConfig;
use std::collections::BTreeMap;
use std::ops::ControlFlow;
use std::path::Path;

/// A context's number in its [`System`] (libspe2's `spe_context_ptr_t`), in the order the
/// contexts were created.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct ContextId(pub usize);

/// How a context runs; results are the same for either engine.
#[derive(Clone, Default)]
pub struct ContextConfig {
    /// The block compiler ([`Engine::Jit`]) or the interpreter.
    pub engine: Engine,
    /// The cycle-level timing model's settings, or `None` for one cycle per instruction.
    pub timing: Option<TimingConfig>,
    /// Compiled blocks shared with other contexts (and other systems): a block is
    /// compiled once for every context running the same code. `None`: the context's own.
    pub code: Option<CodeCache>,
    /// The ISA extensions the context decodes and times (`docs/extensions.md`); none
    /// by default, as on the real SPU.
    pub extensions: spu_isa::Extensions,
}

/// When quanta end. Within a quantum every SPU runs on its own; main-memory writes and
/// signals between SPUs take effect at its end.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quantum {
    /// Quanta end at multiples of this many cycles of a clock shared by all contexts;
    /// one that would pass the run's cycle limit ends at the limit instead, so that a run
    /// cut by it leaves every running context at exactly the limit (and a resumed run's
    /// quanta end at the multiples again).
    Aligned(u64),
    /// Each quantum ends this many cycles after the slowest running context's clock, or
    /// at the run's cycle limit (a single SPU run as `Spu::run` runs it).
    FromSlowest(u64),
}

impl Default for Quantum {
    fn default() -> Quantum {
        Quantum::FromSlowest(4096)
    }
}

/// Where a context stands.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum State {
    /// It runs when the system runs.
    Runnable,
    /// It waits on a channel only the host (or another SPU's signal) makes ready; `pc`
    /// is the channel instruction, which runs again when the context resumes.
    Waiting {
        /// The channel.
        channel: Channel,
        /// The channel instruction's address.
        pc: u32,
    },
    /// It stopped and is not resumed (no handler took the stop, or one said to stop).
    Stopped(StopReason),
    /// A stop handler or PPE-assisted call refused what the program asked: the message,
    /// and the address of the `stop` instruction.
    Faulted {
        /// The `stop` instruction's address.
        pc: u32,
        /// Why.
        message: String,
    },
}

/// A context waiting on a channel, as a run reports it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Wait {
    /// The context.
    pub context: ContextId,
    /// What it waits on.
    pub channel: Channel,
    /// The channel instruction's address.
    pub pc: u32,
}

/// How a run ended.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// Every context has stopped or faulted (see [`System::state`]).
    Stopped,
    /// Every context still running waits on a channel the host serves: write the
    /// mailboxes or signals (or read the outbound mailboxes) and run again.
    Waiting(Vec<Wait>),
    /// As [`Outcome::Waiting`], but the host served nothing since the last run came back
    /// waiting: nothing can make progress.
    Deadlock(Vec<Wait>),
    /// The cycle limit came first; running again with a higher limit goes on.
    CycleLimit,
    /// The observer of [`System::run_observed`] ended the run; running again goes on.
    Interrupted,
}

/// What a stop handler decides.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Resume {
    /// Resume the program after the `stop` (the handler may have moved its pc).
    Continue,
    /// Leave it stopped, with the stop code as its end.
    Stop,
}

/// A stopped context as a handler sees it: the stop code, its SPU (registers, local store,
/// pc just after the `stop`) and main memory.
pub struct Stopped<'a> {
    /// The context.
    pub context: ContextId,
    /// The 14-bit stop code.
    pub code: u16,
    /// Its SPU.
    pub spu: &'a mut Spu,
    /// The system's main memory.
    pub memory: &'a mut MainMemory,
}

/// A PPE-assisted call as its class's handler sees it (libspe2's handlers got the local
/// store and this word).
pub struct LibraryCall<'a> {
    /// The context.
    pub context: ContextId,
    /// The word after the `stop`: the opcode in its top byte, the local-store address of
    /// the argument block in its low 24 bits.
    pub opdata: u32,
    /// Its SPU (pc at the data word; the system resumes it after the word).
    pub spu: &'a mut Spu,
    /// The system's main memory.
    pub memory: &'a mut MainMemory,
}

type StopHandler = Box<dyn FnMut(&mut Stopped) -> Result<Resume, String>>;

/// SPU contexts sharing a main memory, run together deterministically: the same results
/// for any number of host threads and either engine. See the crate documentation.
pub struct System {
    spus: Vec<Spu>,
    states: Vec<State>,
    memory: MainMemory,
    quantum: Quantum,
    threads: usize,
    /// The shared clock: where the last quantum ended.
    now: u64,
    handlers: BTreeMap<u16, StopHandler>,
    /// The default C99 and POSIX.1 handlers (made when first needed, without a root).
    host: Option<Host>,
    /// The host served a channel since the last run came back waiting.
    served: bool,
}

impl System {
    /// A system with `memory_bytes` of zeroed main memory and no contexts.
    pub fn new(memory_bytes: usize) -> System {
        System::with_memory(MainMemory::zeroed(memory_bytes))
    }

    /// A system over `memory`, the caller's main-memory image (the SPUs' DMA target).
    pub fn with_memory(memory: MainMemory) -> System {
        System {
            spus: Vec::new(),
            states: Vec::new(),
            memory,
            quantum: Quantum::default(),
            threads: 1,
            now: 0,
            handlers: BTreeMap::new(),
            host: None,
            served: true,
        }
    }

    /// Sets when quanta end.
    pub fn set_quantum(&mut self, quantum: Quantum) {
        self.quantum = quantum;
    }

    /// Sets how many host threads run the SPUs (1 by default; the results are the same).
    pub fn set_threads(&mut self, threads: usize) {
        self.threads = threads.max(1);
    }

    /// The one host directory the default PPE-assisted file calls may reach (none
    /// without it; the standard streams are always the host's).
    pub fn set_root(&mut self, root: Option<&Path>) -> Result<(), String> {
        self.host = Some(Host::new(root)?);
        Ok(())
    }

    /// What the default PPE-assisted calls hold open: (streams `fopen` handed out and
    /// not closed, POSIX.1 descriptors open, the standard three included).
    pub fn open_files(&self) -> (usize, usize) {
        self.host
            .as_ref()
            .map_or((0, 0), |h| (h.c99.open_files(), h.posix1.open_count()))
    }

    /// Creates a context (libspe2's `spe_context_create`): SPU number `n` for the n-th,
    /// reset (registers and local store zero, pc 0), runnable.
    pub fn create_context(&mut self, config: ContextConfig) -> ContextId {
        let id = ContextId(self.spus.len());
        let mut spu = Spu::new(id.0 as u32);
        spu.host_feeds = true;
        spu.set_engine(config.engine);
        spu.set_extensions(config.extensions);
        if let Some(code) = &config.code {
            spu.share_code(code);
        }
        if let Some(timing) = config.timing {
            spu.enable_timing(timing);
        }
        self.spus.push(spu);
        self.states.push(State::Runnable);
        self.served = true;
        id
    }

    /// Loads `program` into context `id` and sets its entry state as the SDK's loader
    /// did (`start`: as `elfspe` ran it from a shell, or as `spe_context_run` with argp
    /// and envp); the state, for `--dump-entry`.
    pub fn load(
        &mut self,
        id: ContextId,
        program: &Program,
        start: &Start,
    ) -> Result<Entry, LoadError> {
        let entry = start::prepare(start, program.end(), self.memory.len()).map_err(LoadError)?;
        let spu = &mut self.spus[id.0];
        let segments: Vec<(u32, &[u8])> = program
            .segments
            .iter()
            .map(|(a, d)| (*a, d.as_slice()))
            .collect();
        spu.load_segments(&segments, program.entry);
        start::apply(&entry, spu, &mut self.memory);
        if let Some((image, ear)) = &program.overlay_image {
            // libspe2: the whole image in main memory (here just below the argv
            // region, or the top), its effective address in `_EAR_`.
            let top = entry
                .argv
                .as_ref()
                .map_or(self.memory.len() as u64, |a| a.ea);
            let ea = top
                .checked_sub(image.len() as u64)
                .map(|e| e & !127)
                .ok_or_else(|| {
                    LoadError(format!(
                        "the overlay program's image ({} bytes) does not fit main memory                          ({} bytes)",
                        image.len(),
                        self.memory.len()
                    ))
                })?;
            self.memory.bytes_mut()[ea as usize..ea as usize + image.len()].copy_from_slice(image);
            spu.write_ls(*ear, &ea.to_be_bytes());
        }
        self.states[id.0] = State::Runnable;
        self.served = true;
        Ok(entry)
    }

    /// Loads an SPU ELF executable (bytes) into context `id` (libspe2's
    /// `spe_image_open` and `spe_program_load`), with the entry state `start`.
    pub fn load_elf(
        &mut self,
        id: ContextId,
        elf: &[u8],
        start: &Start,
    ) -> Result<Entry, LoadError> {
        let program = Program::from_elf(elf)?;
        self.load(id, &program, start)
    }

    /// Loads the SPU ELF executable (or raw image) at `path` into context `id`.
    pub fn load_elf_file(
        &mut self,
        id: ContextId,
        path: &Path,
        start: &Start,
    ) -> Result<Entry, LoadError> {
        let program = Program::from_file(path)?;
        self.load(id, &program, start)
    }

    /// The contexts, in order.
    pub fn contexts(&self) -> impl Iterator<Item = ContextId> {
        (0..self.spus.len()).map(ContextId)
    }

    /// Where context `id` stands.
    pub fn state(&self, id: ContextId) -> &State {
        &self.states[id.0]
    }

    /// Context `id`'s SPU: registers, local store, cycles, statistics.
    pub fn spu(&self, id: ContextId) -> &Spu {
        &self.spus[id.0]
    }

    /// Context `id`'s SPU, writable (between runs).
    pub fn spu_mut(&mut self, id: ContextId) -> &mut Spu {
        self.served = true;
        &mut self.spus[id.0]
    }

    /// Context `id`'s local store (libspe2's `spe_ls_area_get`).
    pub fn ls(&self, id: ContextId) -> &[u8] {
        self.spus[id.0].ls()
    }

    /// Main memory.
    pub fn memory(&self) -> &MainMemory {
        &self.memory
    }

    /// Main memory, writable (between runs).
    pub fn memory_mut(&mut self) -> &mut MainMemory {
        &mut self.memory
    }

    /// Gives main memory back to the caller.
    pub fn into_memory(self) -> MainMemory {
        self.memory
    }

    /// Writes context `id`'s inbound mailbox (4 deep; libspe2's `spe_in_mbox_write`):
    /// false when it is full.
    pub fn write_in_mbox(&mut self, id: ContextId, value: u32) -> bool {
        self.served = true;
        self.spus[id.0].write_inbound_mailbox(value)
    }

    /// Entries waiting in context `id`'s inbound mailbox.
    pub fn in_mbox_len(&self, id: ContextId) -> usize {
        self.spus[id.0].inbound_mailbox_len()
    }

    /// Takes context `id`'s outbound mailbox value (`spe_out_mbox_read`), if any.
    pub fn read_out_mbox(&mut self, id: ContextId) -> Option<u32> {
        let v = self.spus[id.0].read_outbound_mailbox();
        self.served |= v.is_some();
        v
    }

    /// Takes context `id`'s outbound interrupt mailbox value
    /// (`spe_out_intr_mbox_read`), if any.
    pub fn read_out_intr_mbox(&mut self, id: ContextId) -> Option<u32> {
        let v = self.spus[id.0].read_outbound_interrupt_mailbox();
        self.served |= v.is_some();
        v
    }

    /// Writes one of context `id`'s signal-notification registers
    /// (`spe_signal_write`; ORed in where the register is in OR mode).
    pub fn write_signal(&mut self, id: ContextId, signal: Signal, value: u32) {
        self.served = true;
        self.spus[id.0].write_signal(signal.index(), value);
    }

    /// Runs `handler` whenever a context stops with `code` (as libspe2's
    /// `spe_callback_handler_register`), instead of leaving it stopped. It replaces any
    /// handler of that code, the default PPE-assisted classes' included.
    pub fn register_stop_handler(
        &mut self,
        code: u16,
        handler: impl FnMut(&mut Stopped) -> Result<Resume, String> + 'static,
    ) {
        self.handlers.insert(code & 0x3fff, Box::new(handler));
    }

    /// Serves PPE-assisted call class `class` (stop code `0x2100 | class`) with
    /// `handler`: it gets the data word and the SPU, and the program resumes after the
    /// word. Classes 0 (C99) and 1 (POSIX.1) have defaults with a sandbox
    /// ([`System::set_root`]); registering one replaces the default.
    pub fn register_call_handler(
        &mut self,
        class: u8,
        mut handler: impl FnMut(&mut LibraryCall) -> Result<(), String> + 'static,
    ) {
        self.register_stop_handler(*CALL_STOPS.start() | class as u16, move |stopped| {
            let pc = stopped.spu.pc();
            let ls = stopped.spu.ls();
            let word = ls.get(pc as usize..pc as usize + 4).ok_or_else(|| {
                format!("the call's data word at {pc:#x} lies outside local store")
            })?;
            let opdata = u32::from_be_bytes([word[0], word[1], word[2], word[3]]);
            handler(&mut LibraryCall {
                context: stopped.context,
                opdata,
                spu: stopped.spu,
                memory: stopped.memory,
            })?;
            stopped.spu.set_pc(pc + 4);
            Ok(Resume::Continue)
        });
    }

    /// Runs until every context has stopped, every running one waits on the host, or
    /// a context's clock reaches `max_cycles`.
    pub fn run(&mut self, max_cycles: u64) -> Outcome {
        self.run_observed(max_cycles, |_, _| ControlFlow::Continue(()))
    }

    /// As [`System::run`], calling `observe` with main memory and every context's state
    /// after each quantum (for progress reports); it may end the run early.
    pub fn run_observed(
        &mut self,
        max_cycles: u64,
        mut observe: impl FnMut(&MainMemory, &[State]) -> ControlFlow<()>,
    ) -> Outcome {
        let waits = self.waits();
        let runnable = self.states.contains(&State::Runnable);
        if !runnable && !waits.is_empty() {
            if !self.served {
                return Outcome::Deadlock(waits);
            }
            for w in &waits {
                self.states[w.context.0] = State::Runnable;
            }
        }
        self.served = false;
        let mut outcome = Outcome::Stopped;
        let System {
            spus,
            states,
            memory,
            quantum,
            threads,
            now,
            handlers,
            host,
            ..
        } = self;
        let (quantum, threads) = (*quantum, *threads);
        // The limit is exact on every context, as `Spu::run`'s is, however the quanta fall.
        for spu in spus.iter_mut() {
            spu.set_cycle_limit(max_cycles);
        }
        let result: Result<(), ()> = run_quanta(spus, memory, threads, |spus, memory, outcomes| {
            if let Some(outcomes) = outcomes {
                apply_quantum(spus, memory);
                let mut all_blocked = true;
                for (i, stop) in outcomes.into_iter().enumerate() {
                    if !matches!(stop, Some(StopReason::Blocked { .. }))
                        && matches!(states[i], State::Runnable | State::Waiting { .. })
                    {
                        all_blocked = false;
                    }
                    let Some(stop) = stop else { continue };
                    states[i] = match stop {
                        StopReason::Blocked { channel } => State::Waiting {
                            channel: Channel::from_number(channel),
                            pc: spus[i].pc(),
                        },
                        StopReason::Stop(code) => {
                            serve_stop(ContextId(i), code, &mut spus[i], memory, handlers, host)
                        }
                        other => State::Stopped(other),
                    };
                }
                if observe(memory, states).is_break() {
                    outcome = Outcome::Interrupted;
                    return Ok(Next::Done);
                }
                let runnable = states.contains(&State::Runnable);
                let waiting = states.iter().any(|s| matches!(s, State::Waiting { .. }));
                if !runnable && (!waiting || all_blocked) {
                    outcome = if waiting {
                        Outcome::Waiting(Vec::new())
                    } else {
                        Outcome::Stopped
                    };
                    return Ok(Next::Done);
                }
            }
            // Waiting contexts try again while others run: another SPU may signal them.
            let running: Vec<bool> = states
                .iter()
                .map(|s| matches!(s, State::Runnable | State::Waiting { .. }))
                .collect();
            let slowest = spus
                .iter()
                .zip(&running)
                .filter(|(_, r)| **r)
                .map(|(s, _)| s.cycles())
                .min();
            let Some(slowest) = slowest else {
                outcome = Outcome::Stopped;
                return Ok(Next::Done);
            };
            if slowest >= max_cycles {
                outcome = Outcome::CycleLimit;
                return Ok(Next::Done);
            }
            let until = match quantum {
                Quantum::Aligned(n) => {
                    if *now >= max_cycles {
                        // Only contexts waiting on another are left, and the clock is out.
                        outcome = Outcome::CycleLimit;
                        return Ok(Next::Done);
                    }
                    let n = n.max(1);
                    (*now / n)
                        .saturating_add(1)
                        .saturating_mul(n)
                        .min(max_cycles)
                }
                Quantum::FromSlowest(n) => slowest.saturating_add(n.max(1)).min(max_cycles),
            };
            *now = until;
            Ok(Next::Run { until, running })
        });
        let _ = result;
        for spu in self.spus.iter_mut() {
            spu.set_cycle_limit(u64::MAX);
        }
        if let Outcome::Waiting(_) = outcome {
            outcome = Outcome::Waiting(self.waits());
        }
        outcome
    }

    /// The contexts that wait, in order.
    fn waits(&self) -> Vec<Wait> {
        self.states
            .iter()
            .enumerate()
            .filter_map(|(i, s)| match s {
                State::Waiting { channel, pc } => Some(Wait {
                    context: ContextId(i),
                    channel: *channel,
                    pc: *pc,
                }),
                _ => None,
            })
            .collect()
    }
}

/// What becomes of a context that stopped with `code`: a handler's decision, a
/// default PPE-assisted call served, or stopped.
fn serve_stop(
    context: ContextId,
    code: u16,
    spu: &mut Spu,
    memory: &mut MainMemory,
    handlers: &mut BTreeMap<u16, StopHandler>,
    host: &mut Option<Host>,
) -> State {
    let stop_pc = spu.pc().wrapping_sub(4);
    if let Some(handler) = handlers.get_mut(&code) {
        let mut stopped = Stopped {
            context,
            code,
            spu,
            memory,
        };
        return match handler(&mut stopped) {
            Ok(Resume::Continue) => State::Runnable,
            Ok(Resume::Stop) => State::Stopped(StopReason::Stop(code)),
            Err(message) => State::Faulted {
                pc: stop_pc,
                message,
            },
        };
    }
    if CALL_STOPS.contains(&code) {
        let host = match host {
            Some(h) => h,
            None => match Host::new(None) {
                Ok(h) => host.insert(h),
                Err(message) => {
                    return State::Faulted {
                        pc: stop_pc,
                        message,
                    }
                }
            },
        };
        return match host.serve(spu, code) {
            Ok(()) => State::Runnable,
            Err(fault) => State::Faulted {
                pc: stop_pc,
                message: fault.0,
            },
        };
    }
    State::Stopped(StopReason::Stop(code))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn elf(source: &str) -> Vec<u8> {
        spu_asm::assemble(source, "test.s", &Default::default())
            .unwrap_or_else(|d| panic!("{}", d[0]))
            .elf
    }

    /// Each SPU adds its argp to `$12` 300 times, putting the sum to the same main-memory
    /// quadword (0x800) each time, then gets that quadword back: the SPUs race on it.
    const RACE: &str = "
_start: il      $10, 300
        shlqbyi $20, $4, 4
        il      $12, 0
        il      $13, 0x1000
        il      $14, 0x800
        il      $15, 16
        il      $16, 0
        il      $17, 0x20
        il      $18, 1
        il      $19, 2
loop:   a       $12, $12, $20
        stqa    $12, 0x1000
        wrch    $MFC_LSA, $13
        wrch    $MFC_EAH, $16
        wrch    $MFC_EAL, $14
        wrch    $MFC_Size, $15
        wrch    $MFC_TagID, $16
        wrch    $MFC_Cmd, $17
        wrch    $MFC_WrTagMask, $18
        wrch    $MFC_WrTagUpdate, $19
        rdch    $21, $MFC_RdTagStat
        ai      $10, $10, -1
        brnz    $10, loop
        il      $22, 0x1100
        wrch    $MFC_LSA, $22
        wrch    $MFC_EAL, $14
        il      $23, 0x40
        wrch    $MFC_Cmd, $23
        wrch    $MFC_WrTagUpdate, $19
        rdch    $21, $MFC_RdTagStat
        stop    0x2000
";

    /// Per SPU (cycles, `$12`, the word it got back), and main memory's 0x800.
    fn race(threads: usize, engine: Engine, timing: bool) -> (Vec<(u64, u32, u32)>, u32) {
        let program = elf(RACE);
        let mut system = System::new(1 << 16);
        system.set_threads(threads);
        system.set_quantum(Quantum::Aligned(500));
        let ids: Vec<_> = (1..=3u64)
            .map(|i| {
                let id = system.create_context(ContextConfig {
                    engine,
                    timing: timing.then(TimingConfig::default),
                    code: None,
                    extensions: Default::default(),
                });
                let start = Start::Api {
                    argp: 0x10 * i,
                    envp: 0,
                };
                system.load_elf(id, &program, &start).unwrap();
                id
            })
            .collect();
        assert_eq!(system.run(10_000_000), Outcome::Stopped);
        let word = |b: &[u8]| u32::from_be_bytes([b[0], b[1], b[2], b[3]]);
        let spus = ids
            .iter()
            .map(|&id| {
                assert_eq!(*system.state(id), State::Stopped(StopReason::Stop(0x2000)));
                let spu = system.spu(id);
                (spu.cycles(), spu.reg(12)[0], word(&spu.ls()[0x1100..]))
            })
            .collect();
        (spus, system.memory().read_u32(0x800))
    }

    #[test]
    fn contexts_run_alike_on_any_number_of_threads_and_either_engine() {
        for timing in [false, true] {
            let (spus, last) = race(1, Engine::Interp, timing);
            // Each SPU's own sum is exact; the race's winner is the same every time.
            let sums: Vec<u32> = spus.iter().map(|s| s.1).collect();
            assert_eq!(sums, [300 * 0x10, 300 * 0x20, 300 * 0x30]);
            assert!(sums.contains(&last), "{last:#x}");
            for threads in [1, 2, 3] {
                for engine in [Engine::Interp, Engine::host_default()] {
                    assert_eq!(
                        race(threads, engine, timing),
                        (spus.clone(), last),
                        "{threads} threads, {engine:?}, timing {timing}"
                    );
                }
            }
        }
    }

    #[test]
    fn a_call_class_handler_gets_the_data_word_and_the_program_resumes_after_it() {
        // stop 0x2105 then its data word (opcode 7, block at 0x200); then exit with $3.
        let program = elf("_start: stop 0x2105\n .long 0x07000200\n stop 0x2000\n");
        let mut system = System::new(4096);
        let id = system.create_context(ContextConfig::default());
        system
            .load_elf(id, &program, &Start::Api { argp: 0, envp: 0 })
            .unwrap();
        let seen = std::rc::Rc::new(std::cell::Cell::new(0));
        let saw = seen.clone();
        system.register_call_handler(5, move |call| {
            saw.set(call.opdata);
            call.spu.set_reg(3, [99, 0, 0, 0]);
            Ok(())
        });
        assert_eq!(system.run(1000), Outcome::Stopped);
        assert_eq!(seen.get(), 0x0700_0200);
        assert_eq!(*system.state(id), State::Stopped(StopReason::Stop(0x2000)));
        assert_eq!(system.spu(id).reg(3)[0], 99);
        assert_eq!(system.spu(id).pc(), 12);
    }

    #[test]
    fn an_unknown_call_class_faults_naming_class_and_opcode() {
        let program = elf("_start: stop 0x2107\n .long 0x03000200\n stop 0x2000\n");
        let mut system = System::new(4096);
        let id = system.create_context(ContextConfig::default());
        system
            .load_elf(id, &program, &Start::Api { argp: 0, envp: 0 })
            .unwrap();
        assert_eq!(system.run(1000), Outcome::Stopped);
        assert_eq!(
            *system.state(id),
            State::Faulted {
                pc: 0,
                message: "stop 0x2107: PPE-assisted call class 7 (opcode 3) is not one this \
                          host serves (0 = C99, 1 = POSIX.1)"
                    .into()
            }
        );
    }

    #[test]
    fn the_cycle_limit_leaves_the_run_resumable() {
        let program = elf("_start: il $3, 1000\nl: ai $3, $3, -1\n brnz $3, l\n stop 0x2000\n");
        let mut system = System::new(4096);
        let id = system.create_context(ContextConfig::default());
        system
            .load_elf(id, &program, &Start::Api { argp: 0, envp: 0 })
            .unwrap();
        assert_eq!(system.run(100), Outcome::CycleLimit);
        assert_eq!(system.spu(id).cycles(), 100);
        assert_eq!(system.run(10_000), Outcome::Stopped);
        // il, 1000 passes of ai and brnz, stop: one cycle each without the timing model.
        assert_eq!(system.spu(id).cycles(), 2002);
    }
}
