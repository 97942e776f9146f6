//! Translation of one block to Cranelift IR and host code, the code cache the SPUs of a
//! machine share, and each SPU's table of the blocks it runs compiled.

use std::collections::HashMap;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Condvar, Mutex};
use std::time::Instant;

use cranelift_codegen::ir::condcodes::IntCC;
use cranelift_codegen::ir::types::{F32X4, I32, I32X4, I64, I8, I8X16};
use cranelift_codegen::ir::{
    AbiParam, Block as IrBlock, BlockArg, ConstantData, Endianness, InstBuilder, MemFlagsData,
    Signature, UserFuncName, Value,
};
use cranelift_codegen::isa::CallConv;
use cranelift_codegen::settings::{self, Configurable};
use cranelift_codegen::Context;
use cranelift_frontend::{FunctionBuilder, FunctionBuilderContext};
use cranelift_jit::{JITBuilder, JITModule};
use cranelift_module::{default_libcall_names, Module};

use super::helpers::{exact_run_entry, helper_for, BRANCH, TAKEN};
use super::Compiling;
use crate::analysis::is_branch;
use crate::codec::Inst;
use crate::machine::exec::{execute_in, Core, Reg, LS_MASK, LS_SIZE};
use crate::table::Op;
use crate::timing::may_fall_through;

/// The longest block compiled: the timing memo's limit.
pub(crate) use crate::timing::MAX_BLOCK;

/// What a compiled block reads and writes. Offsets are fixed: the block loads them.
#[repr(C)]
pub(crate) struct Ctx {
    /// The core's register file (`[Reg; 128]`).
    pub regs: *mut Reg,
    /// Local store, `LS_SIZE` bytes.
    pub ls: *mut u8,
    /// One byte per local-store quadword: nonzero where the quadword may hold decoded code.
    pub code_quads: *mut u8,
    pub core: *mut Core,
    /// The SPU, for the store hook.
    pub spu: *mut u8,
    /// Out: the target of the block's final branch.
    pub target: u32,
    pub _pad: u32,
    /// In: the instructions the call may run. A block whose final branch goes back to its
    /// start runs again while the whole next pass fits (0 or less than twice its length:
    /// it runs once); a store into decoded code sets it to 0.
    pub budget: u64,
    /// Out: the passes through a self-looping block before the last one.
    pub loops: u64,
}

const CTX_REGS: i32 = 0;
const CTX_LS: i32 = 8;
const CTX_QUADS: i32 = 16;
const CTX_CORE: i32 = 24;
const CTX_TARGET: i32 = 40;
const CTX_BUDGET: i32 = 48;
const CTX_LOOPS: i32 = 56;

/// Called after a store into a quadword that may hold decoded code: `(ctx, address,
/// address of the next instruction, end of the block, whether instructions follow in the
/// block)`; marks the words stale and returns nonzero when the store wrote the rest of the
/// block (which must then end).
pub(crate) type StoreHook = unsafe extern "C" fn(*mut Ctx, u32, u32, u32, u32) -> u32;

/// A compiled block's entry: returns the next address (bits 0..31), the instructions done
/// (bits 32..47), whether its final branch was taken (bit 48) and whether it ended early
/// after a store into its own rest (bit 49).
pub(crate) type Entry = unsafe extern "C" fn(*mut Ctx) -> u64;
pub(crate) const RESULT_TAKEN: u64 = 1 << 48;
pub(crate) const RESULT_PARTIAL: u64 = 1 << 49;

/// The most registers a self-loop carries from pass to pass as values: beyond the host's
/// vector registers they are spilled, and the loop's back edge moves every one of them,
/// which costs more (in compiling above all) than loading them again from the register
/// file, which the block keeps up to date anyway.
const MAX_CARRIED: usize = 12;

/// Cranelift's optimisation level for blocks: "none" compiles a room frame's blocks about a
/// third faster but its code runs slower, a net loss (docs/timing.md, "Block compiler").
const OPT_LEVEL: &str = "speed";

fn new_module() -> JITModule {
    let mut flags = settings::builder();
    flags.set("opt_level", OPT_LEVEL).expect("opt_level");
    flags
        .set("use_colocated_libcalls", "false")
        .expect("libcalls");
    flags.set("is_pic", "false").expect("is_pic");
    if !cfg!(debug_assertions) {
        flags.set("enable_verifier", "false").expect("verifier");
    }
    let isa = cranelift_native::builder()
        .expect("host supported by Cranelift")
        .finish(settings::Flags::new(flags))
        .expect("host ISA");
    JITModule::new(JITBuilder::with_isa(isa, default_libcall_names()))
}

/// Blocks compiled into one code memory before the cache starts another (code memory is
/// only freed whole), and blocks one SPU keeps before it starts over.
const MAX_BLOCKS: usize = 1 << 14;

/// One compiled block, shared by every SPU of the machine whose local store holds the
/// same words at the same address.
pub(crate) struct Code {
    pub entry: Entry,
    pub n: u32,
    /// The words compiled, to check against local store when the code epoch moved.
    pub words: Box<[u32]>,
    /// The final instruction (a branch, or not).
    pub last: Inst,
    /// The final branch may go back to the block's start, and then the code runs the
    /// block again while the budget holds a further pass ([`Ctx::budget`]).
    pub self_loop: bool,
    /// The instructions whose helpers take them by address.
    _insts: Box<[Inst]>,
    /// The code memory holding `entry`, freed when its last block is gone.
    _memory: Arc<CodeMemory>,
}

/// A Cranelift module's code memory, freed when the last block compiled into it is gone.
struct CodeMemory(Mutex<Option<JITModule>>);

// SAFETY: the module is only used under its mutex; nothing in it refers to thread-local
// state, and its code is position-fixed memory any thread may run.
unsafe impl Send for CodeMemory {}
unsafe impl Sync for CodeMemory {}

impl Drop for CodeMemory {
    fn drop(&mut self) {
        let module = self.0.get_mut().unwrap_or_else(|e| e.into_inner()).take();
        if let Some(module) = module {
            // SAFETY: every entry into this module's code was held by a `Code`, which
            // held this memory alive; all are gone.
            unsafe { module.free_memory() };
        }
    }
}

/// What a compiled block's code depends on besides the fixed store hook: its address (for
/// relative branches, loads and links) and its words.
type Key = (u32, Box<[u32]>);

/// The compiler, for all SPUs of a machine (one block at a time).
struct Compiler {
    memory: Arc<CodeMemory>,
    ctx: Context,
    fctx: FunctionBuilderContext,
    scratch: Box<Core>,
    /// Functions declared in `memory`'s module (their names).
    functions: u32,
}

// SAFETY: as for `CodeMemory`: used only under the cache's mutex.
unsafe impl Send for Compiler {}

/// What the cache holds for a block.
#[derive(Clone)]
enum Made {
    Code(Arc<Code>),
    /// The compiler declined it (an instruction it cannot translate).
    Declined,
    /// Asked of the background compiler, not done yet; how often SPUs started the block
    /// meanwhile (its [`Demand`]).
    Queued(Demand),
}

/// How often SPUs started a block while it waited for the background compiler: the
/// compiler takes the waiting block with the most instructions interpreted for want of it
/// first, so that the hot loops a frame spends its time in run compiled soonest. (In the
/// order asked, the blocks of a 1024x1024 room frame's hottest loops came 32nd to 74th of
/// 90, 0.2-0.4 s after the first.) What is compiled first changes only how much runs compiled.
pub(crate) type Demand = Arc<AtomicU64>;

/// What an SPU asking for a block's code gets.
pub(crate) enum Lookup {
    Ready(Arc<Code>),
    /// The block cannot be compiled.
    Declined,
    /// The background compiler has it in its queue: interpret the block meanwhile and ask
    /// again once [`CodeCache::completed`] moved, adding to its [`Demand`] each time.
    Pending(Demand),
}

/// A block for the background compiler.
struct Request {
    key: Key,
    pc: u32,
    insts: Box<[Inst]>,
    hook: StoreHook,
    demand: Demand,
}

impl Request {
    /// The instructions interpreted so far for want of this block's code.
    fn want(&self) -> u64 {
        self.demand
            .load(Ordering::Relaxed)
            .saturating_mul(self.insts.len() as u64)
    }
}

/// The background compiler's queue of blocks, and whether the cache is gone.
#[derive(Default)]
struct Queue {
    waiting: Mutex<(Vec<Request>, bool)>,
    asked: Condvar,
}

impl Queue {
    /// Adds a block, unless the compiler's thread has gone.
    fn push(&self, request: Request) -> bool {
        let mut guard = self.waiting.lock().unwrap_or_else(|e| e.into_inner());
        if guard.1 {
            return false;
        }
        guard.0.push(request);
        self.asked.notify_one();
        true
    }

    /// The waiting block most wanted (the first asked among equals), after waiting for
    /// one; `None` once the cache is gone.
    fn next(&self) -> Option<Request> {
        let mut guard = self.waiting.lock().unwrap_or_else(|e| e.into_inner());
        loop {
            if guard.1 {
                return None;
            }
            if !guard.0.is_empty() {
                let mut best = 0;
                let mut most = guard.0[0].want();
                for (k, r) in guard.0.iter().enumerate().skip(1) {
                    let want = r.want();
                    if want > most {
                        (best, most) = (k, want);
                    }
                }
                return Some(guard.0.remove(best));
            }
            guard = self.asked.wait(guard).unwrap_or_else(|e| e.into_inner());
        }
    }

    /// Ends the compiler's thread.
    fn close(&self) {
        let mut guard = self.waiting.lock().unwrap_or_else(|e| e.into_inner());
        guard.1 = true;
        guard.0.clear();
        self.asked.notify_all();
    }
}

struct Shared {
    /// The blocks made, looked up without waiting for a compile in progress.
    made: Mutex<HashMap<Key, Made>>,
    compiler: Mutex<Compiler>,
    /// What was compiled so far, apart from the compiler so that reading it does not wait
    /// for a compile in progress.
    stats: Mutex<super::JitStats>,
    /// Blocks the background compiler finished (made or declined).
    completed: AtomicU64,
    /// The background compiler's queue; `None`: the asking SPU compiles the block itself.
    requests: Option<Arc<Queue>>,
}

impl Drop for Shared {
    fn drop(&mut self) {
        if let Some(queue) = &self.requests {
            queue.close();
        }
    }
}

/// The compile cache of a machine: every SPU given the same cache (with
/// [`crate::machine::Spu::share_code`]) compiles each block once, whichever SPU gets there
/// first. What an SPU runs, and so every cycle and counter, does not depend on it: each
/// SPU decides by its own counts which of its blocks to run compiled, and a block's code
/// depends only on its address and words.
///
/// A cache made [`CodeCache::with`] [`Compiling::Background`] compiles on a host thread
/// of its own: SPUs asking for a block not compiled yet go on interpreting it meanwhile,
/// so compiling takes no time from the simulation (on a host with a core to spare), and
/// what runs compiled, only that, depends on the host's timing.
#[derive(Clone)]
pub struct CodeCache(Arc<Shared>);

impl Default for CodeCache {
    fn default() -> Self {
        CodeCache::new()
    }
}

impl CodeCache {
    /// A cache compiling inline ([`Compiling::default`]).
    pub fn new() -> CodeCache {
        CodeCache::with(Compiling::default())
    }

    /// An empty cache that compiles hot blocks the way `compiling` says.
    pub fn with(compiling: Compiling) -> CodeCache {
        let module = new_module();
        let ctx = module.make_context();
        let compiler = Mutex::new(Compiler {
            memory: Arc::new(CodeMemory(Mutex::new(Some(module)))),
            ctx,
            fctx: FunctionBuilderContext::new(),
            scratch: Box::new(Core::new()),
            functions: 0,
        });
        let made = Mutex::new(HashMap::new());
        let completed = AtomicU64::new(0);
        if compiling == Compiling::Inline {
            return CodeCache(Arc::new(Shared {
                made,
                compiler,
                stats: Mutex::default(),
                completed,
                requests: None,
            }));
        }
        let queue = Arc::new(Queue::default());
        let shared = Arc::new(Shared {
            made,
            compiler,
            stats: Mutex::default(),
            completed,
            requests: Some(queue.clone()),
        });
        let weak = Arc::downgrade(&shared);
        // The thread holds the cache only while it compiles: it ends when the last SPU
        // dropped the cache (which closes the queue).
        let spawned = std::thread::Builder::new()
            .name("spu-jit".into())
            .spawn(move || {
                while let Some(r) = queue.next() {
                    let Some(shared) = weak.upgrade() else {
                        return;
                    };
                    shared.compile(r.key, r.pc, &r.insts, r.hook);
                    shared.completed.fetch_add(1, Ordering::Release);
                }
            });
        match spawned {
            Ok(_) => CodeCache(shared),
            // No thread to be had: compile inline.
            Err(_) => CodeCache::with(Compiling::Inline),
        }
    }

    /// Blocks compiled, their instructions and the host seconds spent (for all SPUs of
    /// the cache; `compiled_instructions` is left 0).
    pub fn stats(&self) -> super::JitStats {
        *self.0.stats.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// How the cache compiles: on a thread of its own, or on the asking SPU's.
    pub fn compiling(&self) -> Compiling {
        if self.0.requests.is_some() {
            Compiling::Background
        } else {
            Compiling::Inline
        }
    }

    /// How many blocks the background compiler finished (compiled or declined) so far.
    pub fn completed(&self) -> u64 {
        self.0.completed.load(Ordering::Acquire)
    }

    /// The code for `insts` at `pc`: made by some SPU already, else compiled now (or put
    /// in the background compiler's queue).
    pub(crate) fn code(&self, pc: u32, insts: &[Inst], hook: StoreHook) -> Lookup {
        let n = insts.len();
        if n == 0
            || n > MAX_BLOCK
            || insts[..n - 1]
                .iter()
                .any(|&i| is_branch(i.op) && !may_fall_through(i))
            || insts.iter().any(|i| i.op == Op::Bisled)
        {
            return Lookup::Declined;
        }
        let key: Key = (pc, insts.iter().map(|i| i.word).collect());
        let Some(requests) = &self.0.requests else {
            return self.0.compile(key, pc, insts, hook);
        };
        let mut made = self.0.made.lock().unwrap_or_else(|e| e.into_inner());
        match made.get(&key) {
            Some(Made::Code(code)) => Lookup::Ready(code.clone()),
            Some(Made::Declined) => Lookup::Declined,
            Some(Made::Queued(demand)) => Lookup::Pending(demand.clone()),
            None => {
                let demand = Demand::default();
                made.insert(key.clone(), Made::Queued(demand.clone()));
                let request = Request {
                    key,
                    pc,
                    insts: insts.into(),
                    hook,
                    demand: demand.clone(),
                };
                if requests.push(request) {
                    Lookup::Pending(demand)
                } else {
                    Lookup::Declined
                }
            }
        }
    }
}

impl Shared {
    /// The code for `insts` at `pc` (`key`; checked by [`CodeCache::code`]), compiled now
    /// unless it was made already.
    fn compile(&self, key: Key, pc: u32, insts: &[Inst], hook: StoreHook) -> Lookup {
        let n = insts.len();
        let mut guard = self.compiler.lock().unwrap_or_else(|e| e.into_inner());
        let c = &mut *guard;
        {
            let mut made = self.made.lock().unwrap_or_else(|e| e.into_inner());
            match made.get(&key) {
                Some(Made::Code(code)) => return Lookup::Ready(code.clone()),
                Some(Made::Declined) => return Lookup::Declined,
                _ => {}
            }
            if made.len() >= MAX_BLOCKS {
                // Code memory is only freed whole: a new module; the old one goes when
                // the last SPU drops its blocks.
                let module = new_module();
                c.ctx = module.make_context();
                c.memory = Arc::new(CodeMemory(Mutex::new(Some(module))));
                made.clear();
                c.functions = 0;
            }
        }
        let started = Instant::now();
        let owned: Box<[Inst]> = insts.into();
        let self_loop = self_loop(pc, &owned[n - 1], pc.wrapping_add(4 * (n as u32 - 1)));
        let made = match c.translate(pc, &owned, hook, self_loop) {
            Some(entry) => {
                let mut stats = self.stats.lock().unwrap_or_else(|e| e.into_inner());
                stats.blocks += 1;
                stats.block_instructions += n as u64;
                stats.compile_seconds += started.elapsed().as_secs_f64();
                Made::Code(Arc::new(Code {
                    entry,
                    n: n as u32,
                    words: key.1.clone(),
                    last: owned[n - 1],
                    self_loop,
                    _insts: owned,
                    _memory: c.memory.clone(),
                }))
            }
            None => Made::Declined,
        };
        let mut all = self.made.lock().unwrap_or_else(|e| e.into_inner());
        all.insert(key, made.clone());
        match made {
            Made::Code(code) => Lookup::Ready(code),
            _ => Lookup::Declined,
        }
    }
}

/// Whether `last` (at `at`) is a direct branch that may go back to `pc`.
fn self_loop(pc: u32, last: &Inst, at: u32) -> bool {
    use Op::*;
    let imm = (last.imm << 2) as u32;
    let target = match last.op {
        Br | Brz | Brnz | Brhz | Brhnz => at.wrapping_add(imm),
        Bra => imm,
        _ => return false,
    };
    target & LS_MASK & !3 == pc & LS_MASK
}

/// A block as one SPU knows it: the shared code and the code epoch at which the SPU last
/// found the block's words in its local store.
pub(crate) struct Block {
    pub code: Arc<Code>,
    pub verified: u64,
}

/// One SPU's compiled blocks, found by their first word's index.
pub(crate) struct Blocks {
    cache: CodeCache,
    /// Per local-store word: 1 + index into `blocks` of the block starting there, or 0.
    pub slots: Vec<u32>,
    /// Per local-store word: how often a block started there without compiled code.
    pub heat: Vec<u8>,
    pub blocks: Vec<Block>,
    /// Per local-store word: 0, or for a block waiting for the background compiler, the
    /// cache's [`CodeCache::completed`] when last asked, as [`asked`] keeps it (asked
    /// again once it moved).
    pub pending: Vec<u32>,
    /// Per local-store word of a block waiting for the background compiler: its
    /// [`Demand`], and the times the block started interpreted.
    pub demand: HashMap<u32, (Demand, u32)>,
    /// Distinguishes this table (and each time it starts over) from every other its SPU
    /// had: what the SPU kept of a block (its entry, in its own timing memo) holds while
    /// this stays the same. A count per SPU from 1, so that no process-wide counter is
    /// needed ([`crate::machine::Spu::share_code`] continues it).
    pub generation: u64,
}

/// [`CodeCache::completed`] as [`Blocks::pending`] keeps it: never 0.
pub(crate) fn asked(completed: u64) -> u32 {
    (completed % u32::MAX as u64) as u32 + 1
}

impl Blocks {
    /// An empty table compiling into `cache`, its SPU's `generation`th.
    pub fn new(cache: CodeCache, generation: u64) -> Blocks {
        Blocks {
            cache,
            slots: vec![0; LS_SIZE / 4],
            heat: vec![0; LS_SIZE / 4],
            blocks: Vec::new(),
            pending: vec![0; LS_SIZE / 4],
            demand: HashMap::new(),
            generation,
        }
    }

    pub fn cache(&self) -> &CodeCache {
        &self.cache
    }

    /// Compiles `insts` (starting at `pc`), or takes the machine's code for them, and
    /// makes it the block at `pc`; else why not (yet).
    pub fn compile(&mut self, pc: u32, insts: &[Inst], hook: StoreHook) -> Result<usize, Lookup> {
        let code = match self.cache.code(pc, insts, hook) {
            Lookup::Ready(code) => code,
            other => return Err(other),
        };
        if self.blocks.len() >= MAX_BLOCKS {
            self.blocks.clear();
            self.generation += 1;
            self.slots.fill(0);
        }
        let id = self.blocks.len();
        self.blocks.push(Block {
            code,
            verified: u64::MAX,
        });
        self.slots[(pc as usize >> 2) & (LS_SIZE / 4 - 1)] = id as u32 + 1;
        Ok(id)
    }
}

impl Compiler {
    fn translate(
        &mut self,
        pc: u32,
        insts: &[Inst],
        hook: StoreHook,
        self_loop: bool,
    ) -> Option<Entry> {
        let memory = self.memory.clone();
        let mut guard = memory.0.lock().unwrap_or_else(|e| e.into_inner());
        let module = guard.as_mut()?;
        let ptr = module.target_config().pointer_type();
        debug_assert_eq!(ptr, I64);
        module.clear_context(&mut self.ctx);
        let target = module.target_config();
        let call_conv = target.default_call_conv;
        let sig = &mut self.ctx.func.signature;
        sig.params.push(AbiParam::new(I64));
        sig.returns.push(AbiParam::new(I64));
        self.ctx.func.name = UserFuncName::user(0, self.functions);
        self.functions += 1;
        let mut b = FunctionBuilder::new(&mut self.ctx.func, &mut self.fctx);
        let start = b.create_block();
        b.append_block_params_for_function_params(start);
        b.switch_to_block(start);
        let ctx = b.block_params(start)[0];
        let mut t = Translator {
            regs: b.ins().load(I64, MemFlagsData::trusted(), ctx, CTX_REGS),
            ls: b.ins().load(I64, MemFlagsData::trusted(), ctx, CTX_LS),
            quads: b.ins().load(I64, MemFlagsData::trusted(), ctx, CTX_QUADS),
            core: b.ins().load(I64, MemFlagsData::trusted(), ctx, CTX_CORE),
            ctx,
            cache: [None; 128],
            helper_sig: {
                let mut s = Signature::new(call_conv);
                s.params.push(AbiParam::new(I64));
                s.params.push(AbiParam::new(I64));
                s.params.push(AbiParam::new(I32));
                s.returns.push(AbiParam::new(I64));
                b.import_signature(s)
            },
            exact_sig: {
                let (_, preserving) = exact_run_entry();
                let mut s = Signature::new(if preserving {
                    CallConv::PreserveAll
                } else {
                    call_conv
                });
                s.params.push(AbiParam::new(I64));
                s.params.push(AbiParam::new(I64));
                s.params.push(AbiParam::new(I32));
                s.params.push(AbiParam::new(I32));
                b.import_signature(s)
            },
            hook_sig: {
                let mut s = Signature::new(call_conv);
                s.params.push(AbiParam::new(I64));
                for _ in 0..4 {
                    s.params.push(AbiParam::new(I32));
                }
                s.returns.push(AbiParam::new(I32));
                b.import_signature(s)
            },
            hook,
            scratch: &mut self.scratch,
            deferred: None,
            carried: Vec::new(),
            b,
        };
        // The block's instructions start in a block of their own, so that a self-loop can
        // jump back to them. A self-loop carries the registers it reads from one pass to
        // the next as values (the register file in memory stays up to date too): the
        // next pass reads them without loading them again.
        let body = t.b.create_block();
        if self_loop {
            let mut read: Vec<u8> = insts
                .iter()
                .flat_map(|&i| crate::analysis::operands(i).reads)
                .flatten()
                .map(|r| r & 127)
                .collect();
            read.sort_unstable();
            read.dedup();
            if read.len() <= MAX_CARRIED {
                t.carried = read;
            }
        }
        let first: Vec<BlockArg> = (0..t.carried.len())
            .map(|i| {
                t.b.append_block_param(body, I32X4);
                BlockArg::Value(t.get(t.carried[i]))
            })
            .collect();
        t.b.ins().jump(body, &first);
        t.b.switch_to_block(body);
        t.cache = [None; 128];
        for (i, &r) in t.carried.iter().enumerate() {
            t.cache[r as usize] = Some(t.b.block_params(body)[i]);
        }
        let n = insts.len();
        let block_end = pc.wrapping_add(4 * n as u32);
        let mut done = false;
        let mut k = 0;
        while k < n {
            let inst = &insts[k];
            let p = pc.wrapping_add(4 * k as u32) & LS_MASK;
            let more = k + 1 < n;
            if is_branch(inst.op) && more {
                t.inner_branch(inst, p, k as u64);
            } else if is_branch(inst.op) {
                t.branch(inst, p, n as u64, self_loop.then_some(body));
                done = true;
            } else if let Some(end) = float_run(insts, k) {
                t.float_run(&insts[k..end], p);
                k = end;
                continue;
            } else {
                t.instruction(inst, p, k as u64, block_end, more);
            }
            k += 1;
        }
        if !done {
            let next = pc.wrapping_add(4 * n as u32) & LS_MASK;
            let r =
                t.b.ins()
                    .iconst(I64, (next as u64 | (n as u64) << 32) as i64);
            t.b.ins().return_(&[r]);
        }
        t.b.seal_all_blocks();
        t.b.finalize(target);
        let id = module
            .declare_anonymous_function(&self.ctx.func.signature)
            .ok()?;
        module.define_function(id, &mut self.ctx).ok()?;
        module.clear_context(&mut self.ctx);
        module.finalize_definitions().ok()?;
        let code = module.get_finalized_function(id);
        // SAFETY: the function was just compiled with the `Entry` signature.
        Some(unsafe { std::mem::transmute::<*const u8, Entry>(code) })
    }
}

/// Where a conditional branch goes when taken.
enum Target {
    Known(u32),
    /// From a register, at run time (an `i32`).
    Register(Value),
}

struct Translator<'a> {
    b: FunctionBuilder<'a>,
    ctx: Value,
    regs: Value,
    ls: Value,
    quads: Value,
    core: Value,
    /// The value of each register as this block last loaded or wrote it.
    cache: [Option<Value>; 128],
    helper_sig: cranelift_codegen::ir::SigRef,
    hook_sig: cranelift_codegen::ir::SigRef,
    /// The call of a float run's exact path ([`exact_run_entry`]).
    exact_sig: cranelift_codegen::ir::SigRef,
    hook: StoreHook,
    scratch: &'a mut Core,
    /// Inside a run of float arithmetic: the registers written so far, whose stores wait
    /// until the run's one check has chosen the fast or the exact path.
    deferred: Option<Vec<usize>>,
    /// A self-loop's registers carried from pass to pass as the body's parameters.
    carried: Vec<u8>,
}

/// Whether the host has fused multiply-add (Cranelift's `fma` is one instruction there).
fn host_fma() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::is_x86_feature_detected!("fma")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// Whether the host's vector unit does this single-precision operation inline (`fa`,
/// `fs`, `fm` on x86_64; the fused ones where the host has fused multiply-add).
fn host_float(op: Op) -> bool {
    use Op::*;
    match op {
        Fa | Fs | Fm => cfg!(target_arch = "x86_64"),
        Fma | Fms | Fnms => host_fma(),
        _ => false,
    }
}

/// Whether `Translator::instruction` emits this operation as pure register code (no
/// memory but the registers, no call, no side effect), so that it may sit inside a float
/// run and be done again by the interpreter's semantics on the run's exact path.
fn register_only(op: Op) -> bool {
    use Op::*;
    matches!(
        op,
        Nop | Lnop
            | Il
            | Ilh
            | Ilhu
            | Ila
            | Iohl
            | Fsmbi
            | A
            | Ai
            | Sf
            | Sfi
            | And
            | Andc
            | Or
            | Orc
            | Xor
            | Nand
            | Nor
            | Eqv
            | Andi
            | Ori
            | Xori
            | Ceq
            | Cgt
            | Clgt
            | Ceqi
            | Cgti
            | Clgti
            | Selb
            | Shufb
            | Shli
            | Rotmi
            | Rotmai
            | Roti
            | Rotqbyi
            | Shlqbyi
            | Rotqmbyi
            | Fceq
            | Fcgt
            | Fcmeq
            | Fcmgt
    )
}

/// The end (exclusive) of the float run starting at `insts[k]`, if one starts there: from
/// a float operation the host does inline, over register-only instructions, to the last
/// such float operation before anything else.
fn float_run(insts: &[Inst], k: usize) -> Option<usize> {
    if !host_float(insts[k].op) {
        return None;
    }
    let mut end = k + 1;
    for (j, inst) in insts.iter().enumerate().skip(k + 1) {
        if host_float(inst.op) {
            end = j + 1;
        } else if !register_only(inst.op) {
            break;
        }
    }
    Some(end)
}

/// For each 4-bit `m` (word `i` in bit `i`): word `i` moved to bit `3 - i`.
static REVERSED_LANES: [u32; 16] = {
    let mut t = [0; 16];
    let mut m = 0;
    while m < 16 {
        let mut i = 0;
        while i < 4 {
            if m & (1 << i) != 0 {
                t[m] |= 1 << (3 - i);
            }
            i += 1;
        }
        m += 1;
    }
    t
};

/// Host byte position of each big-endian byte of a register (words are host-order).
const fn host(j: usize) -> u8 {
    (j ^ 3) as u8
}

impl Translator<'_> {
    fn flags() -> MemFlagsData {
        MemFlagsData::new().with_notrap()
    }

    fn get(&mut self, r: u8) -> Value {
        let r = r as usize & 127;
        if let Some(v) = self.cache[r] {
            return v;
        }
        let v = self
            .b
            .ins()
            .load(I32X4, Self::flags(), self.regs, 16 * r as i32);
        self.cache[r] = Some(v);
        v
    }

    fn set(&mut self, r: u8, v: Value) {
        let r = r as usize & 127;
        match &mut self.deferred {
            Some(written) => written.push(r),
            None => {
                self.b
                    .ins()
                    .store(Self::flags(), v, self.regs, 16 * r as i32);
            }
        }
        self.cache[r] = Some(v);
    }

    fn bytes(&mut self, v: Value) -> Value {
        let le = MemFlagsData::new().with_endianness(Endianness::Little);
        self.b.ins().bitcast(I8X16, le, v)
    }

    fn words(&mut self, v: Value) -> Value {
        let le = MemFlagsData::new().with_endianness(Endianness::Little);
        self.b.ins().bitcast(I32X4, le, v)
    }

    fn vconst(&mut self, r: Reg) -> Value {
        let mut bytes = Vec::with_capacity(16);
        for w in r {
            bytes.extend(w.to_le_bytes());
        }
        let c = self.b.func.dfg.constants.insert(ConstantData::from(bytes));
        self.b.ins().vconst(I32X4, c)
    }

    fn splat(&mut self, x: u32) -> Value {
        self.vconst([x; 4])
    }

    /// `shuffle` of the bytes of `a` and `b` by host positions (16.. pick from `b`).
    fn shuffle(&mut self, a: Value, b: Value, mask: [u8; 16]) -> Value {
        let (a, b) = (self.bytes(a), self.bytes(b));
        let imm = self
            .b
            .func
            .dfg
            .immediates
            .push(ConstantData::from(mask.to_vec()));
        let r = self.b.ins().shuffle(a, b, imm);
        self.words(r)
    }

    /// The byte swap of each word between local store (big-endian) and a register.
    fn swap_words(&mut self, v: Value) -> Value {
        let mut mask = [0u8; 16];
        for (h, m) in mask.iter_mut().enumerate() {
            *m = host(h);
        }
        let imm = self
            .b
            .func
            .dfg
            .immediates
            .push(ConstantData::from(mask.to_vec()));
        self.b.ins().shuffle(v, v, imm)
    }

    /// The local-store address of quadword-aligned `addr` (a 32-bit value), as a pointer.
    fn ls_address(&mut self, addr: Value) -> (Value, Value) {
        let a = self.b.ins().band_imm_u(addr, (LS_MASK & !15) as i64);
        let wide = self.b.ins().uextend(I64, a);
        (a, self.b.ins().iadd(self.ls, wide))
    }

    fn preferred(&mut self, v: Value) -> Value {
        self.b.ins().extractlane(v, 0)
    }

    fn address(&mut self, inst: &Inst, p: u32) -> Value {
        let imm = inst.imm;
        match inst.op {
            Op::Lqd | Op::Stqd => {
                let ra = self.get(inst.ra);
                let a = self.preferred(ra);
                self.b.ins().iadd_imm_s(a, (imm << 4) as i64)
            }
            Op::Lqx | Op::Stqx => {
                let (ra, rb) = (self.get(inst.ra), self.get(inst.rb));
                let (a, b) = (self.preferred(ra), self.preferred(rb));
                self.b.ins().iadd(a, b)
            }
            Op::Lqa | Op::Stqa => self.b.ins().iconst(I32, ((imm << 2) as u32) as i64),
            _ => self
                .b
                .ins()
                .iconst(I32, (p.wrapping_add((imm << 2) as u32)) as i64),
        }
    }

    /// The result of an instruction that only reads immediates, computed now by the
    /// interpreter itself.
    fn constant_of(&mut self, inst: &Inst, p: u32) -> Value {
        let _ = execute_in::<false>(self.scratch, *inst, p);
        let r = self.scratch.regs[inst.rt as usize & 127];
        self.vconst(r)
    }

    /// A call of the interpreter's semantics for `inst` (at `p`), which reads and writes
    /// the registers in memory.
    fn emit_helper(&mut self, inst: &Inst, p: u32) -> cranelift_codegen::ir::Inst {
        let f = helper_for(inst.op);
        let callee = self.b.ins().iconst(I64, f as usize as i64);
        let ip = self
            .b
            .ins()
            .iconst(I64, inst as *const Inst as usize as i64);
        let pc = self.b.ins().iconst(I32, p as i64);
        self.b
            .ins()
            .call_indirect(self.helper_sig, callee, &[self.core, ip, pc])
    }

    fn call_helper(&mut self, inst: &Inst, p: u32) -> Value {
        let call = self.emit_helper(inst, p);
        // The helper wrote its result in memory.
        self.cache = [None; 128];
        self.b.inst_results(call)[0]
    }

    /// Emits one non-branch instruction.
    fn instruction(&mut self, inst: &Inst, p: u32, k: u64, block_end: u32, more: bool) {
        use Op::*;
        let i10 = inst.imm as u32;
        macro_rules! bin {
            ($f:ident) => {{
                let (a, b) = (self.get(inst.ra), self.get(inst.rb));
                let v = self.b.ins().$f(a, b);
                self.set(inst.rt, v)
            }};
        }
        macro_rules! imm {
            ($f:ident) => {{
                let a = self.get(inst.ra);
                let c = self.splat(i10);
                let v = self.b.ins().$f(a, c);
                self.set(inst.rt, v)
            }};
        }
        macro_rules! cmp {
            ($cc:expr, $b:expr) => {{
                let a = self.get(inst.ra);
                let b = $b;
                let v = self.b.ins().icmp($cc, a, b);
                self.set(inst.rt, v)
            }};
        }
        match inst.op {
            Nop | Lnop | Hbra | Hbrr => {}
            // The timing model takes the hint entry's target from the core.
            Hbr if !crate::timing::is_hbrp(*inst) => {
                let ra = self.get(inst.ra);
                let t = self.preferred(ra);
                let t = self.b.ins().band_imm_u(t, (LS_MASK & !3) as i64);
                let at = std::mem::offset_of!(Core, hint_target) as i32;
                self.b
                    .ins()
                    .store(MemFlagsData::trusted(), t, self.core, at);
            }
            Hbr => {}
            // An MFC command parameter's latch (other channel instructions end blocks).
            Wrch if crate::analysis::is_mfc_param_write(*inst) => {
                let rt = self.get(inst.rt);
                let v = self.preferred(rt);
                let field = crate::machine::exec::MfcParams::offset(inst.ra);
                let at = (std::mem::offset_of!(Core, mfc) + field) as i32;
                self.b
                    .ins()
                    .store(MemFlagsData::trusted(), v, self.core, at);
            }
            Il | Ilh | Ilhu | Ila | Fsmbi => {
                let v = self.constant_of(inst, p);
                self.set(inst.rt, v)
            }
            Iohl => {
                let t = self.get(inst.rt);
                let c = self.splat(inst.imm as u32 & 0xffff);
                let v = self.b.ins().bor(t, c);
                self.set(inst.rt, v)
            }
            A => bin!(iadd),
            Ai => imm!(iadd),
            Sf => {
                let (a, b) = (self.get(inst.ra), self.get(inst.rb));
                let v = self.b.ins().isub(b, a);
                self.set(inst.rt, v)
            }
            Sfi => {
                let a = self.get(inst.ra);
                let c = self.splat(i10);
                let v = self.b.ins().isub(c, a);
                self.set(inst.rt, v)
            }
            And => bin!(band),
            Andc => bin!(band_not),
            Or => bin!(bor),
            Orc => bin!(bor_not),
            Xor => bin!(bxor),
            Nand | Nor | Eqv => {
                let (a, b) = (self.get(inst.ra), self.get(inst.rb));
                let v = match inst.op {
                    Nand => self.b.ins().band(a, b),
                    Nor => self.b.ins().bor(a, b),
                    _ => self.b.ins().bxor(a, b),
                };
                let v = self.b.ins().bnot(v);
                self.set(inst.rt, v)
            }
            Andi => imm!(band),
            Ori => imm!(bor),
            Xori => imm!(bxor),
            Ceq => cmp!(IntCC::Equal, self.get(inst.rb)),
            Cgt => cmp!(IntCC::SignedGreaterThan, self.get(inst.rb)),
            Clgt => cmp!(IntCC::UnsignedGreaterThan, self.get(inst.rb)),
            Ceqi => cmp!(IntCC::Equal, self.splat(i10)),
            Cgti => cmp!(IntCC::SignedGreaterThan, self.splat(i10)),
            Clgti => cmp!(IntCC::UnsignedGreaterThan, self.splat(i10)),
            Selb => {
                let (a, b, c) = (self.get(inst.ra), self.get(inst.rb), self.get(inst.rc));
                let v = self.b.ins().bitselect(c, b, a);
                self.set(inst.rt, v)
            }
            Shufb => {
                let (a, b, c) = (self.get(inst.ra), self.get(inst.rb), self.get(inst.rc));
                let v = self.shufb(a, b, c);
                self.set(inst.rt, v)
            }
            Shli | Rotmi | Rotmai | Roti => {
                let a = self.get(inst.ra);
                let v = self.word_shift(inst.op, a, inst.imm as u32);
                self.set(inst.rt, v)
            }
            Rotqbyi | Shlqbyi | Rotqmbyi => {
                let a = self.get(inst.ra);
                let imm = inst.imm as u32;
                // Result byte j (big-endian) takes source byte `from(j)`, or zero.
                let from = |j: u32| -> Option<u32> {
                    match inst.op {
                        Rotqbyi => Some((j + (imm & 15)) & 15),
                        Shlqbyi => {
                            let c = imm & 0x1f;
                            (j + c < 16).then_some(j + c)
                        }
                        _ => {
                            let c = imm.wrapping_neg() & 0x1f;
                            (j >= c && c < 16).then(|| j - c)
                        }
                    }
                };
                let mut mask = [0u8; 16];
                for j in 0..16u32 {
                    mask[host(j as usize) as usize] = match from(j) {
                        Some(s) => host(s as usize),
                        None => 16,
                    };
                }
                let zero = self.splat(0);
                let v = self.shuffle(a, zero, mask);
                self.set(inst.rt, v)
            }
            Fceq | Fcgt | Fcmeq | Fcmgt => {
                let (a, b) = (self.get(inst.ra), self.get(inst.rb));
                let magnitude = matches!(inst.op, Fcmeq | Fcmgt);
                let (ka, kb) = (self.sp_key(a, magnitude), self.sp_key(b, magnitude));
                let cc = if matches!(inst.op, Fceq | Fcmeq) {
                    IntCC::Equal
                } else {
                    IntCC::SignedGreaterThan
                };
                let v = self.b.ins().icmp(cc, ka, kb);
                self.set(inst.rt, v)
            }
            Frest | Frsqest => {
                let a = self.get(inst.ra);
                let v = self.estimate(a, inst.op == Frsqest);
                self.set(inst.rt, v)
            }
            Gb => {
                // Bit 0 of each word, word 0 the highest of four, in the preferred word.
                let a = self.get(inst.ra);
                let k = self.b.ins().iconst(I32, 31);
                let low = self.b.ins().ishl(a, k);
                let lanes = self.b.ins().vhigh_bits(I32, low);
                let bits = self.reverse_lane_bits(lanes);
                let v = self.b.ins().scalar_to_vector(I32X4, bits);
                self.set(inst.rt, v)
            }
            Fi => {
                let (x, est) = (self.get(inst.ra), self.get(inst.rb));
                let v = self.fi(x, est);
                self.set(inst.rt, v)
            }
            Cflts | Cfltu => {
                let a = self.get(inst.ra);
                let v = self.float_to_int(a, inst.op == Cflts, inst.imm as u32);
                self.set(inst.rt, v)
            }
            Lqd | Lqx | Lqa | Lqr => {
                let addr = self.address(inst, p);
                let (_, at) = self.ls_address(addr);
                let raw = self.b.ins().load(I8X16, Self::flags(), at, 0);
                let swapped = self.swap_words(raw);
                let v = self.words(swapped);
                self.set(inst.rt, v)
            }
            Stqd | Stqx | Stqa | Stqr => {
                let addr = self.address(inst, p);
                let (a, at) = self.ls_address(addr);
                let t = self.get(inst.rt);
                let bytes = self.bytes(t);
                let swapped = self.swap_words(bytes);
                self.b.ins().store(Self::flags(), swapped, at, 0);
                self.after_store(a, p, k, block_end, more);
            }
            _ => {
                self.call_helper(inst, p);
            }
        }
    }

    /// A run of single-precision arithmetic (`fa`, `fs`, `fm`, `fma`, `fms`, `fnms`) and the
    /// register-only instructions between them (`float_run` chooses it): each operation
    /// is the host's vector operation (the block runs with the host's floating point
    /// truncating, as the interpreter's fast loops do), and one check over the whole run
    /// takes that path where the interpreter's fast path takes it for every operation,
    /// with that path's criteria lane for lane (`exec::sp4_truncating`: every operand
    /// normal or zero, the result normal and not the largest magnitude, or a zero that
    /// cannot be an underflow). Otherwise the whole run is done again from the registers
    /// it started with by the interpreter's semantics, instruction by instruction, which
    /// gives the exact results and flags. The run's register writes wait for the check.
    fn float_run(&mut self, run: &[Inst], p: u32) {
        self.deferred = Some(Vec::new());
        // Results of the run's float operations: if the run's check holds, each is a
        // normal number or +0, so as a later operand it needs no check of its own.
        let mut ordinary = Vec::new();
        let mut all_good: Option<Value> = None;
        for (k, inst) in run.iter().enumerate() {
            let at = p.wrapping_add(4 * k as u32) & LS_MASK;
            if host_float(inst.op) {
                let (result, good) = self.single_precision(inst, &ordinary);
                all_good = Some(match all_good {
                    Some(g) => self.b.ins().band(g, good),
                    None => good,
                });
                ordinary.push(result);
                self.set(inst.rt, result);
            } else {
                self.instruction(inst, at, 0, 0, true);
            }
        }
        let mut written = self.deferred.take().unwrap_or_default();
        written.sort_unstable();
        written.dedup();
        let all = self
            .b
            .ins()
            .vall_true(all_good.expect("a run starts with a float operation"));
        let fast = self.b.create_block();
        let exact = self.b.create_block();
        let cont = self.b.create_block();
        self.b.ins().brif(all, fast, &[], exact, &[]);
        self.b.switch_to_block(fast);
        for &r in &written {
            let v = self.cache[r].expect("a written register is cached");
            self.b
                .ins()
                .store(Self::flags(), v, self.regs, 16 * r as i32);
        }
        self.b.ins().jump(cont, &[]);
        self.b.switch_to_block(exact);
        // One call for the whole run, which keeps every register where the host allows.
        let (f, _) = exact_run_entry();
        let callee = self.b.ins().iconst(I64, f as i64);
        let insts = self.b.ins().iconst(I64, run.as_ptr() as usize as i64);
        let at = self.b.ins().iconst(I32, p as i64);
        let n = self.b.ins().iconst(I32, run.len() as i64);
        self.b
            .ins()
            .call_indirect(self.exact_sig, callee, &[self.core, insts, at, n]);
        self.b.ins().jump(cont, &[]);
        self.b.switch_to_block(cont);
        // Both paths wrote the run's results to memory; every other register is as before.
        for r in written {
            self.cache[r] = None;
        }
    }

    /// One single-precision operation of a float run on the host's vector unit: its
    /// result and the lanes where the interpreter's fast path gives that result (operands
    /// in `ordinary` are known to pass the operand criteria).
    ///
    /// The lanes are the interpreter's (`sp4_truncating`: operands normal or zero, result
    /// normal below the largest magnitude, or a zero that cannot be an underflow), checked
    /// with fewer host instructions. An operand with exponent 255 is not looked at: the
    /// host's sum, product or fused multiply-add of an infinity or NaN is an infinity or
    /// NaN, which the result check declines, so only denormal operands need a check of
    /// their own. Each range is one signed compare after a wrapping add that moves it to
    /// the top of the signed words.
    fn single_precision(&mut self, inst: &Inst, ordinary: &[Value]) -> (Value, Value) {
        use Op::*;
        let three = matches!(inst.op, Fma | Fms | Fnms);
        let (a, b) = (self.get(inst.ra), self.get(inst.rb));
        let c = if three { Some(self.get(inst.rc)) } else { None };
        let abs = self.splat(0x7fff_ffff);
        let zero = self.splat(0);
        let (mag_a, mag_b) = (self.b.ins().band(a, abs), self.b.ins().band(b, abs));
        let mut ok: Option<Value> = None;
        for v in [Some(a), Some(b), c].into_iter().flatten() {
            if ordinary.contains(&v) {
                continue;
            }
            // Not a denormal: magnitude 0 or at least 0x0080_0000. Adding 0x7fff_ffff maps
            // 0 to the largest signed word, denormals to the bottom of the negative words
            // (up to 0x807f_fffe) and the rest above them.
            let m = match v {
                v if v == a => mag_a,
                v if v == b => mag_b,
                v => self.b.ins().band(v, abs),
            };
            let t = self.b.ins().iadd(m, abs);
            let floor = self.splat(0x807f_fffe);
            let o = self.b.ins().icmp(IntCC::SignedGreaterThan, t, floor);
            ok = Some(match ok {
                Some(k) => self.b.ins().band(k, o),
                None => o,
            });
        }
        let le = MemFlagsData::new().with_endianness(Endianness::Little);
        let f = |t: &mut Self, v: Value| t.b.ins().bitcast(F32X4, le, v);
        let (fa, fb) = (f(self, a), f(self, b));
        let r = match inst.op {
            Fa => self.b.ins().fadd(fa, fb),
            Fs => self.b.ins().fsub(fa, fb),
            Fm => self.b.ins().fmul(fa, fb),
            _ => {
                let fc = f(self, c.expect("three operands"));
                match inst.op {
                    Fma => self.b.ins().fma(fa, fb, fc),
                    Fms => {
                        let nc = self.b.ins().fneg(fc);
                        self.b.ins().fma(fa, fb, nc)
                    }
                    _ => {
                        let na = self.b.ins().fneg(fa);
                        self.b.ins().fma(na, fb, fc)
                    }
                }
            }
        };
        let v = self.b.ins().bitcast(I32X4, le, r);
        let mag = self.b.ins().band(v, abs);
        let result_zero = self.b.ins().icmp(IntCC::Equal, mag, zero);
        // Normal below the largest magnitude: 0x0080_0000..=0x7f7f_fffe, moved by
        // 0x0080_0001 to 0x0100_0001..=0x7fff_ffff (larger magnitudes wrap negative).
        let shift = self.splat(0x0080_0001);
        let shifted = self.b.ins().iadd(mag, shift);
        let floor = self.splat(0x0100_0000);
        let normal = self.b.ins().icmp(IntCC::SignedGreaterThan, shifted, floor);
        let zero_ok = if matches!(inst.op, Fa | Fs) {
            result_zero
        } else {
            // A zero product is no underflow where a factor is zero.
            let least = self.b.ins().umin(mag_a, mag_b);
            let factor = self.b.ins().icmp(IntCC::Equal, least, zero);
            self.b.ins().band(result_zero, factor)
        };
        let mut good = self.b.ins().bor(normal, zero_ok);
        if let Some(ok) = ok {
            good = self.b.ins().band(good, ok);
        }
        (self.b.ins().band_not(v, result_zero), good)
    }

    /// The comparison key of each single (`float::sp_key`, or of its magnitude): 0 for a
    /// zero exponent (zeros and denormals), else sign and magnitude as a signed word
    /// (exponent 255 is an ordinary number, so the order is that of the integers).
    fn sp_key(&mut self, v: Value, magnitude: bool) -> Value {
        let abs = self.splat(0x7fff_ffff);
        let exp = self.splat(0x7f80_0000);
        let zero = self.splat(0);
        let mag = self.b.ins().band(v, abs);
        let e = self.b.ins().band(v, exp);
        let tiny = self.b.ins().icmp(IntCC::Equal, e, zero);
        let mag = self.b.ins().band_not(mag, tiny);
        if magnitude {
            return mag;
        }
        let thirty_one = self.b.ins().iconst(I32, 31);
        let sign = self.b.ins().sshr(v, thirty_one);
        let flipped = self.b.ins().bxor(mag, sign);
        self.b.ins().isub(flipped, sign)
    }

    /// `frest` (or `frsqest`) lane by lane, as `float::frest_flags`: the exponent from
    /// the operand's, the fraction from the table by the operand's top fraction bits; a
    /// zero exponent raises the word slot's divide-by-zero flag.
    fn estimate(&mut self, a: Value, sqrt: bool) -> Value {
        let e_mask = self.splat(0xff);
        let k23 = self.b.ins().iconst(I32, 23);
        let e = self.b.ins().ushr(a, k23);
        let e = self.b.ins().band(e, e_mask);
        let zero = self.splat(0);
        let tiny = self.b.ins().icmp(IntCC::Equal, e, zero);
        // The exponent for a nonzero `e`: 253 - e floored at 0, or 190 - ceil(e / 2).
        let exp = if sqrt {
            debug_assert_eq!(crate::float::frsqest_exponent(3), 190 - 2);
            let one = self.splat(1);
            let up = self.b.ins().iadd(e, one);
            let k1 = self.b.ins().iconst(I32, 1);
            let half = self.b.ins().ushr(up, k1);
            let top = self.splat(190);
            self.b.ins().isub(top, half)
        } else {
            debug_assert_eq!(crate::float::frest_exponent(254), 0);
            let top = self.splat(253);
            let least = self.b.ins().umin(e, top);
            self.b.ins().isub(top, least)
        };
        let most = self.splat(255);
        let exp = self.b.ins().bitselect(tiny, most, exp);
        let exp = self.b.ins().ishl(exp, k23);
        let (table, bits): (&[u32], u32) = if sqrt {
            (&crate::float::FRSQEST_FRACTION, 0x3f)
        } else {
            (&crate::float::FREST_FRACTION, 0x1f)
        };
        let k18 = self.b.ins().iconst(I32, 18);
        let index = self.b.ins().ushr(a, k18);
        let index_mask = self.splat(bits);
        let index = self.b.ins().band(index, index_mask);
        let base = self.b.ins().iconst(I64, table.as_ptr() as usize as i64);
        let mut fraction = index;
        for lane in 0..4u8 {
            let i = self.b.ins().extractlane(index, lane);
            let i = self.b.ins().uextend(I64, i);
            let offset = self.b.ins().ishl_imm_u(i, 2);
            let at = self.b.ins().iadd(base, offset);
            let f = self
                .b
                .ins()
                .load(I32, MemFlagsData::trusted().with_readonly(), at, 0);
            fraction = self.b.ins().insertlane(fraction, f, lane);
        }
        let mut v = self.b.ins().bor(exp, fraction);
        if !sqrt {
            let sign = self.splat(0x8000_0000);
            let sign = self.b.ins().band(a, sign);
            v = self.b.ins().bor(v, sign);
        }
        // The flags: lane i's divide-by-zero bit is `Fpscr::dbz_bit(i)`, 11 - i, gb's order
        // moved up by 8.
        debug_assert_eq!(crate::float::Fpscr::dbz_bit(0), 1 << 11);
        let lanes = self.b.ins().vhigh_bits(I32, tiny);
        let flags = self.reverse_lane_bits(lanes);
        let flags = self.b.ins().ishl_imm_u(flags, 8);
        let at = (std::mem::offset_of!(Core, fpscr) + crate::float::Fpscr::DBZ_WORD_OFFSET) as i32;
        let word = self
            .b
            .ins()
            .load(I32, MemFlagsData::trusted(), self.core, at);
        let word = self.b.ins().bor(word, flags);
        self.b
            .ins()
            .store(MemFlagsData::trusted(), word, self.core, at);
        v
    }

    /// Bits 0..3 of `lanes` (one per word, word 0 in bit 0, as `vhigh_bits` gives them)
    /// with word `i`'s bit moved to bit `3 - i`: a load from a table of the 16 cases.
    fn reverse_lane_bits(&mut self, lanes: Value) -> Value {
        let base = self
            .b
            .ins()
            .iconst(I64, REVERSED_LANES.as_ptr() as usize as i64);
        let i = self.b.ins().uextend(I64, lanes);
        let i = self.b.ins().band_imm_u(i, 15);
        let offset = self.b.ins().ishl_imm_u(i, 2);
        let at = self.b.ins().iadd(base, offset);
        self.b
            .ins()
            .load(I32, MemFlagsData::trusted().with_readonly(), at, 0)
    }

    /// `fi` lane by lane, as `float::fi`: the estimate's base less its step times the
    /// operand's low 19 bits, in 32-bit fixed point, renormalised by one bit when the
    /// difference went below 1.0.
    fn fi(&mut self, x: Value, est: Value) -> Value {
        let base_mask = self.splat(0x007f_fc00);
        let step_mask = self.splat(0x3ff);
        let low = self.splat(0x7_ffff);
        let frac_mask = self.splat(0x007f_ffff);
        let keep = self.splat(0xff80_0000);
        let one_exp = self.splat(1 << 23);
        let base = self.b.ins().band(est, base_mask);
        let nine = self.b.ins().iconst(I32, 9);
        let eight = self.b.ins().iconst(I32, 8);
        let base = self.b.ins().ishl(base, nine);
        let step = self.b.ins().band(est, step_mask);
        let y = self.b.ins().band(x, low);
        let ymul = self.b.ins().imul(step, y);
        let t = self.b.ins().isub(base, ymul);
        let adjust = self.b.ins().icmp(IntCC::UnsignedGreaterThan, ymul, base);
        let by8 = self.b.ins().ushr(t, eight);
        let by9 = self.b.ins().ushr(t, nine);
        let frac = self.b.ins().bitselect(adjust, by8, by9);
        let frac = self.b.ins().band(frac, frac_mask);
        let top = self.b.ins().band(est, keep);
        let r = self.b.ins().bor(top, frac);
        let less = self.b.ins().band(adjust, one_exp);
        self.b.ins().isub(r, less)
    }

    /// `cflts`/`cfltu` with the raw I8 field `i8`, as `float::cflts_scale`: scaling by a
    /// constant power of two only moves the exponent, so where the scaled exponent is an
    /// ordinary one the host's saturating truncation gives the exact result; a zero
    /// exponent, before or after scaling, gives 0, and one past 254 a magnitude of at
    /// least 2^127, which saturates just as the true value does (exponent 255 is a number).
    fn float_to_int(&mut self, a: Value, signed: bool, i8: u32) -> Value {
        let scale = 173 - (i8 & 0xff) as i32;
        let e_mask = self.splat(0xff);
        let keep = self.splat(0x807f_ffff);
        let zero = self.splat(0);
        let largest = self.splat(254);
        let shift = self.b.ins().iconst(I32, 23);
        let e = self.b.ins().ushr(a, shift);
        let e = self.b.ins().band(e, e_mask);
        let by = self.splat(scale as u32);
        let scaled = self.b.ins().iadd(e, by);
        let live = self.b.ins().icmp(IntCC::NotEqual, e, zero);
        let positive = self.b.ins().icmp(IntCC::SignedGreaterThan, scaled, zero);
        let live = self.b.ins().band(live, positive);
        let unclamped = scaled;
        let scaled = self.b.ins().smin(scaled, largest);
        let scaled = self.b.ins().ishl(scaled, shift);
        let y = self.b.ins().band(a, keep);
        let y = self.b.ins().bor(y, scaled);
        let y = self.b.ins().band(y, live);
        let le = MemFlagsData::new().with_endianness(Endianness::Little);
        if signed {
            let f = self.b.ins().bitcast(F32X4, le, y);
            return self.b.ins().fcvt_to_sint_sat(I32X4, f);
        }
        // Unsigned: negative values give 0; below 2^31 the signed truncation is exact; at
        // exponent 158 ([2^31, 2^32)) the integer is the significand shifted by 8; above,
        // 0xffffffff.
        let thirty_one = self.b.ins().iconst(I32, 31);
        let negative = self.b.ins().sshr(a, thirty_one);
        let y = self.b.ins().band_not(y, negative);
        let live = self.b.ins().band_not(live, negative);
        let f = self.b.ins().bitcast(F32X4, le, y);
        let low = self.b.ins().fcvt_to_sint_sat(I32X4, f);
        let top = self.splat(158);
        let at_top = self.b.ins().icmp(IntCC::Equal, unclamped, top);
        let at_top = self.b.ins().band(at_top, live);
        let above = self.b.ins().icmp(IntCC::SignedGreaterThan, unclamped, top);
        let above = self.b.ins().band(above, live);
        let fraction = self.splat(0x007f_ffff);
        let one = self.splat(0x0080_0000);
        let m = self.b.ins().band(a, fraction);
        let m = self.b.ins().bor(m, one);
        let eight = self.b.ins().iconst(I32, 8);
        let m = self.b.ins().ishl(m, eight);
        let r = self.b.ins().bitselect(at_top, m, low);
        self.b.ins().bor(r, above)
    }

    /// `shli`, `rotmi`, `rotmai`, `roti` by a constant count, as the interpreter counts.
    fn word_shift(&mut self, op: Op, a: Value, imm: u32) -> Value {
        let amount = |t: &mut Self, c: u32| t.b.ins().iconst(I32, c as i64);
        match op {
            Op::Shli => {
                let c = imm & 0x3f;
                if c > 31 {
                    self.splat(0)
                } else {
                    let s = amount(self, c);
                    self.b.ins().ishl(a, s)
                }
            }
            Op::Rotmi => {
                let c = imm.wrapping_neg() & 0x3f;
                if c > 31 {
                    self.splat(0)
                } else {
                    let s = amount(self, c);
                    self.b.ins().ushr(a, s)
                }
            }
            Op::Rotmai => {
                let c = (imm.wrapping_neg() & 0x3f).min(31);
                let s = amount(self, c);
                self.b.ins().sshr(a, s)
            }
            _ => {
                let c = imm & 0x1f;
                if c == 0 {
                    return a;
                }
                let (l, r) = (amount(self, c), amount(self, 32 - c));
                let hi = self.b.ins().ishl(a, l);
                let lo = self.b.ins().ushr(a, r);
                self.b.ins().bor(hi, lo)
            }
        }
    }

    /// `shufb` on host byte positions: a control byte's index (its low 5 bits, big-endian
    /// numbering) XOR 3 is a host position in RA (0..15) or RB (16..31); top bit set:
    /// 10xxxxxx → 0x00, 110xxxxx → 0xFF, 111xxxxx → 0x80.
    fn shufb(&mut self, a: Value, b: Value, c: Value) -> Value {
        let (a, b, c) = (self.bytes(a), self.bytes(b), self.bytes(c));
        let bconst = |t: &mut Self, x: u8| {
            let v = t.splat(u32::from_ne_bytes([x; 4]));
            t.bytes(v)
        };
        let m1f = bconst(self, 0x1f);
        let three = bconst(self, 3);
        let sixteen = bconst(self, 0x10);
        let idx = self.b.ins().band(c, m1f);
        let idx = self.b.ins().bxor(idx, three);
        // Out-of-range indices (16..31 for RA, after flipping bit 4 for RB) give zero.
        let from_a = self.b.ins().swizzle(a, idx);
        let idx_b = self.b.ins().bxor(idx, sixteen);
        let from_b = self.b.ins().swizzle(b, idx_b);
        let picked = self.b.ins().bor(from_a, from_b);
        let zero = bconst(self, 0);
        let special = self.b.ins().icmp(IntCC::SignedLessThan, c, zero);
        let e0 = bconst(self, 0xe0);
        let c0 = bconst(self, 0xc0);
        let x80 = bconst(self, 0x80);
        let top3 = self.b.ins().band(c, e0);
        let ff = self.b.ins().icmp(IntCC::Equal, top3, c0);
        let is_e0 = self.b.ins().icmp(IntCC::Equal, top3, e0);
        let eighty = self.b.ins().band(is_e0, x80);
        let constant = self.b.ins().bor(ff, eighty);
        let r = self.b.ins().bitselect(special, constant, picked);
        self.words(r)
    }

    /// After a store to (aligned, wrapped) `a`: where local store may hold decoded code
    /// there, the hook marks it stale; the block ends when the hook says so.
    fn after_store(&mut self, a: Value, p: u32, k: u64, block_end: u32, more: bool) {
        let quad = self.b.ins().ushr_imm_u(a, 4);
        let quad = self.b.ins().uextend(I64, quad);
        let at = self.b.ins().iadd(self.quads, quad);
        let flag = self.b.ins().load(I8, Self::flags(), at, 0);
        let hook_block = self.b.create_block();
        let cont = self.b.create_block();
        self.b.ins().brif(flag, hook_block, &[], cont, &[]);
        self.b.switch_to_block(hook_block);
        let next = p.wrapping_add(4) & LS_MASK;
        let callee = self.b.ins().iconst(I64, self.hook as usize as i64);
        let next_v = self.b.ins().iconst(I32, next as i64);
        let end_v = self.b.ins().iconst(I32, block_end as i64);
        let more_v = self.b.ins().iconst(I32, more as i64);
        let call = self.b.ins().call_indirect(
            self.hook_sig,
            callee,
            &[self.ctx, a, next_v, end_v, more_v],
        );
        let exit = self.b.inst_results(call)[0];
        let exit_block: IrBlock = self.b.create_block();
        self.b.ins().brif(exit, exit_block, &[], cont, &[]);
        self.b.switch_to_block(exit_block);
        let r = self
            .b
            .ins()
            .iconst(I64, (next as u64 | (k + 1) << 32 | RESULT_PARTIAL) as i64);
        self.b.ins().return_(&[r]);
        self.b.switch_to_block(cont);
    }

    /// Emits an inner conditional branch (the `k`th instruction, at `p`): taken, the
    /// block returns there, its `k + 1` instructions done ([`RESULT_PARTIAL`] and
    /// [`RESULT_TAKEN`], the target also in the context); untaken, it goes on.
    fn inner_branch(&mut self, inst: &Inst, p: u32, k: u64) {
        debug_assert!(may_fall_through(*inst));
        let (target, taken) = self.condition(inst, p);
        let exit = self.b.create_block();
        let cont = self.b.create_block();
        self.b.ins().brif(taken, exit, &[], cont, &[]);
        self.b.switch_to_block(exit);
        let done = ((k + 1) << 32 | RESULT_TAKEN | RESULT_PARTIAL) as i64;
        let r = match target {
            Target::Known(target) => {
                let t = self.b.ins().iconst(I32, target as i64);
                self.b
                    .ins()
                    .store(MemFlagsData::trusted(), t, self.ctx, CTX_TARGET);
                self.b.ins().iconst(I64, target as i64 | done)
            }
            Target::Register(t) => {
                self.b
                    .ins()
                    .store(MemFlagsData::trusted(), t, self.ctx, CTX_TARGET);
                let t = self.b.ins().uextend(I64, t);
                self.b.ins().bor_imm_u(t, done)
            }
        };
        self.b.ins().return_(&[r]);
        self.b.switch_to_block(cont);
    }

    /// The target of the conditional branch `inst` at `p` ([`may_fall_through`]) and
    /// whether it is taken: for an indirect one, the target is its address register's
    /// preferred word within local store, word-aligned, as the interpreter takes it.
    fn condition(&mut self, inst: &Inst, p: u32) -> (Target, Value) {
        use Op::*;
        if !matches!(inst.op, Biz | Binz | Bihz | Bihnz) {
            let (target, taken) = self.relative_condition(inst, p);
            return (Target::Known(target), taken);
        }
        let taken = self.zero_test(
            inst,
            matches!(inst.op, Bihz | Bihnz),
            matches!(inst.op, Biz | Bihz),
        );
        let ra = self.get(inst.ra);
        let a = self.preferred(ra);
        let target = self.b.ins().band_imm_u(a, (LS_MASK & !3) as i64);
        (Target::Register(target), taken)
    }

    /// The target of the conditional relative branch `inst` at `p` (`brz`, `brnz`, `brhz`,
    /// `brhnz`) and whether it is taken.
    fn relative_condition(&mut self, inst: &Inst, p: u32) -> (u32, Value) {
        use Op::*;
        let target = p.wrapping_add((inst.imm << 2) as u32) & LS_MASK & !3;
        let taken = self.zero_test(
            inst,
            matches!(inst.op, Brhz | Brhnz),
            matches!(inst.op, Brz | Brhz),
        );
        (target, taken)
    }

    /// Whether a conditional branch's register `inst.rt` has its preferred word (or, with
    /// `halfword`, its low halfword) zero (`if_zero`) or nonzero.
    fn zero_test(&mut self, inst: &Inst, halfword: bool, if_zero: bool) -> Value {
        let rt = self.get(inst.rt);
        let v = self.preferred(rt);
        let v = if halfword {
            self.b.ins().band_imm_u(v, 0xffff)
        } else {
            v
        };
        let cc = if if_zero {
            IntCC::Equal
        } else {
            IntCC::NotEqual
        };
        self.b.ins().icmp_imm_u(cc, v, 0)
    }

    /// Emits the block's final branch and its return; with `again`, a taken branch (back
    /// to the block's start) runs the block again from `again` while the budget holds a
    /// whole further pass.
    fn branch(&mut self, inst: &Inst, p: u32, n: u64, again: Option<IrBlock>) {
        use Op::*;
        let next = p.wrapping_add(4) & LS_MASK;
        let imm = inst.imm;
        let done = n << 32;
        let (target, taken): (Value, Value) = match inst.op {
            Br | Bra | Brsl | Brasl => {
                let target = if matches!(inst.op, Br | Brsl) {
                    p.wrapping_add((imm << 2) as u32)
                } else {
                    (imm << 2) as u32
                } & LS_MASK
                    & !3;
                if matches!(inst.op, Brsl | Brasl) {
                    let link = self.vconst([next, 0, 0, 0]);
                    self.set(inst.rt, link);
                }
                let t = self.b.ins().iconst(I32, target as i64);
                let one = self.b.ins().iconst(I8, 1);
                (t, one)
            }
            Brz | Brnz | Brhz | Brhnz => {
                let (target, taken) = self.relative_condition(inst, p);
                let t = self.b.ins().iconst(I32, target as i64);
                (t, taken)
            }
            _ => {
                let code = self.call_helper(inst, p);
                let t = self.b.ins().ireduce(I32, code);
                let taken = self.b.ins().band_imm_u(code, TAKEN as i64);
                let taken = self.b.ins().icmp_imm_u(IntCC::NotEqual, taken, 0);
                const { assert!(BRANCH != 0) };
                (t, taken)
            }
        };
        if let Some(again) = again {
            let check = self.b.create_block();
            let back = self.b.create_block();
            let out = self.b.create_block();
            self.b.ins().brif(taken, check, &[], out, &[]);
            self.b.switch_to_block(check);
            let flags = MemFlagsData::trusted();
            let budget = self.b.ins().load(I64, flags, self.ctx, CTX_BUDGET);
            let more =
                self.b
                    .ins()
                    .icmp_imm_u(IntCC::UnsignedGreaterThanOrEqual, budget, 2 * n as i64);
            self.b.ins().brif(more, back, &[], out, &[]);
            self.b.switch_to_block(back);
            let left = self.b.ins().iadd_imm_s(budget, -(n as i64));
            self.b.ins().store(flags, left, self.ctx, CTX_BUDGET);
            let loops = self.b.ins().load(I64, flags, self.ctx, CTX_LOOPS);
            let loops = self.b.ins().iadd_imm_s(loops, 1);
            self.b.ins().store(flags, loops, self.ctx, CTX_LOOPS);
            let carried: Vec<BlockArg> = (0..self.carried.len())
                .map(|i| BlockArg::Value(self.get(self.carried[i])))
                .collect();
            self.b.ins().jump(again, &carried);
            self.b.switch_to_block(out);
        }
        self.b
            .ins()
            .store(MemFlagsData::trusted(), target, self.ctx, CTX_TARGET);
        let next_v = self.b.ins().iconst(I32, next as i64);
        let to = self.b.ins().select(taken, target, next_v);
        let to = self.b.ins().uextend(I64, to);
        let taken64 = self.b.ins().uextend(I64, taken);
        let taken64 = self.b.ins().ishl_imm_u(taken64, 48);
        let r = self.b.ins().bor_imm_u(to, done as i64);
        let r = self.b.ins().bor(r, taken64);
        self.b.ins().return_(&[r]);
    }
}

#[allow(dead_code)]
fn _assert_layout() {
    use std::mem::offset_of;
    const _: () = assert!(offset_of!(Ctx, regs) == CTX_REGS as usize);
    const _: () = assert!(offset_of!(Ctx, ls) == CTX_LS as usize);
    const _: () = assert!(offset_of!(Ctx, code_quads) == CTX_QUADS as usize);
    const _: () = assert!(offset_of!(Ctx, core) == CTX_CORE as usize);
    const _: () = assert!(offset_of!(Ctx, target) == CTX_TARGET as usize);
    const _: () = assert!(offset_of!(Ctx, budget) == CTX_BUDGET as usize);
    const _: () = assert!(offset_of!(Ctx, loops) == CTX_LOOPS as usize);
}

#[cfg(test)]
mod tests {
    use super::*;

    unsafe extern "C" fn no_hook(_: *mut Ctx, _: u32, _: u32, _: u32, _: u32) -> u32 {
        0
    }

    /// A request for a block of `n` nops at `pc`, started `starts` times while waiting.
    fn request(pc: u32, n: usize, starts: u64) -> Request {
        let insts: Box<[Inst]> = vec![crate::codec::decode(0x4020_0000); n].into();
        Request {
            key: (pc, insts.iter().map(|i| i.word).collect()),
            pc,
            insts,
            hook: no_hook,
            demand: Arc::new(AtomicU64::new(starts)),
        }
    }

    #[test]
    fn the_compiler_takes_the_block_most_interpreted_for_want_of_it_first() {
        let queue = Queue::default();
        // instructions interpreted meanwhile: 4 x 10, 8 x 10, 2 x 40, 80 x 0
        for (pc, n, starts) in [(0, 4, 10), (0x100, 8, 10), (0x200, 2, 40), (0x300, 80, 0)] {
            assert!(queue.push(request(pc, n, starts)));
        }
        let taken = |queue: &Queue| queue.next().map(|r| r.pc);
        // 0x100 and 0x200 tie at 80: the first asked first
        assert_eq!(taken(&queue), Some(0x100));
        assert_eq!(taken(&queue), Some(0x200));
        // a block's demand grows while it waits
        queue.push(request(0x400, 1, 0));
        queue.waiting.lock().unwrap().0[2]
            .demand
            .store(1000, Ordering::Relaxed);
        assert_eq!(taken(&queue), Some(0x400));
        assert_eq!(taken(&queue), Some(0));
        assert_eq!(taken(&queue), Some(0x300));
        // once the cache is gone nothing more is taken or queued
        queue.push(request(0x500, 1, 5));
        queue.close();
        assert_eq!(taken(&queue), None);
        assert!(!queue.push(request(0x600, 1, 5)));
    }
}
