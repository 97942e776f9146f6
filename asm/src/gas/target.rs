//! The SPU target (gas's `tc-spu.c`): register and channel names, operands parsed against
//! each form of a mnemonic from the shared instruction table (`spu_isa::table`) with gas's
//! range checks, immediates encoded (or left as relocations in an object), the `nop` pad
//! words of `tc-spu.c`'s alignment, and the `.sched` block handed to the list scheduler.

use super::read::operand_column;
use super::{Assembler, SchedKey, Severity, LOCAL_STORE};
use crate::expr::Val;
use crate::lex::{split_top, Line};
use spu_isa::table::{forms_named, FormInfo, Format, OperandKind};

/// SPU channel names (`$SPU_RdInMbox`) and their numbers, as gas's `ch_reg_name`.
pub const CHANNELS: &[(&str, u32)] = &[
    ("SPU_RdEventStat", 0),
    ("SPU_WrEventMask", 1),
    ("SPU_WrEventAck", 2),
    ("SPU_RdSigNotify1", 3),
    ("SPU_RdSigNotify2", 4),
    ("SPU_WrDec", 7),
    ("SPU_RdDec", 8),
    ("MFC_WrMSSyncReq", 9),
    ("SPU_RdEventMask", 11),
    ("MFC_RdTagMask", 12),
    ("SPU_RdMachStat", 13),
    ("SPU_WrSRR0", 14),
    ("SPU_RdSRR0", 15),
    ("MFC_LSA", 16),
    ("MFC_EAH", 17),
    ("MFC_EAL", 18),
    ("MFC_Size", 19),
    ("MFC_TagID", 20),
    ("MFC_Cmd", 21),
    ("MFC_WrTagMask", 22),
    ("MFC_WrTagUpdate", 23),
    ("MFC_RdTagStat", 24),
    ("MFC_RdListStallStat", 25),
    ("MFC_WrListStallAck", 26),
    ("MFC_RdAtomicStat", 27),
    ("SPU_WrOutMbox", 28),
    ("SPU_RdInMbox", 29),
    ("SPU_WrOutIntrMbox", 30),
];

/// gas `arg_encode`: field size, position and right shift of an immediate kind, its
/// error range `lo..=hi` and warning range `wlo..=whi` (checked only when hi > lo).
struct ArgEncode {
    size: u32,
    pos: u32,
    rshift: u32,
    lo: i64,
    hi: i64,
    wlo: i64,
    whi: i64,
}

fn arg_encode(kind: OperandKind) -> ArgEncode {
    use OperandKind::*;
    let e = |size, pos, rshift, lo, hi, wlo, whi| ArgEncode {
        size,
        pos,
        rshift,
        lo,
        hi,
        wlo,
        whi,
    };
    match kind {
        S3 | S7n | U3 | U7 => e(7, 14, 0, 0, -1, 0, -1),
        S6 => e(7, 14, 0, -32, 31, -31, 0),
        S7 => e(7, 14, 0, -64, 63, -63, 0),
        U5 => e(7, 14, 0, 0, 127, 0, 31),
        U6 => e(7, 14, 0, 0, 127, 0, 63),
        Scale173 | Scale155 => e(8, 14, 0, 0, 127, 0, -1),
        S10b => e(10, 14, 0, -512, 511, -128, 255),
        S10 => e(10, 14, 0, -512, 511, 0, -1),
        BrInst => e(2, 23, 9, -1024, 1023, 0, -1),
        Off14 => e(10, 14, 4, -8192, 8191, 0, -1),
        S16 => e(16, 7, 0, -32768, 32767, 0, -1),
        Abs18 => e(16, 7, 2, -131072, 262143, 0, -1),
        Rel18 => e(16, 7, 2, -262144, 262143, 0, -1),
        U14 => e(14, 0, 0, 0, 16383, 0, -1),
        X16 => e(16, 7, 0, -32768, 65535, 0, -1),
        U18 => e(18, 7, 0, 0, 262143, 0, -1),
        _ => e(7, 0, 0, 0, -1, 0, -1),
    }
}

/// One parsed operand of an instruction.
enum Operand {
    Reg(OperandKind, i64),
    Imm {
        kind: OperandKind,
        val: Val,
        high: bool,
        low: bool,
        col: usize,
        warnings: Vec<String>,
    },
}

enum CalcErr {
    /// The operands do not have this form's shape (0-based operand index).
    Syntax(usize),
    Hard(usize, String),
    /// A register number outside its field: an error unless another form fits.
    Range(usize, String),
}

/// gas `insn_fmt_string`: `lqd\treg,imm(reg)` with the failing operand in capitals.
fn insn_fmt_string(form: &FormInfo, failing: usize) -> String {
    let mut s = format!("{}\t", form.mnemonic);
    for (i, k) in form.operands.iter().enumerate() {
        let word = if k.is_register() { "reg" } else { "imm" };
        let word = if i == failing {
            word.to_ascii_uppercase()
        } else {
            word.to_string()
        };
        if *k == OperandKind::ParenRa {
            s.push_str(&format!("({word})"));
        } else {
            if i > 0 {
                s.push(',');
            }
            s.push_str(&word);
        }
    }
    s
}

impl Assembler<'_> {
    /// `.sched OPTIONS` ... `.endsched`: the block list-scheduled into dual-issue pairs,
    /// then assembled line by line, each scheduled line keeping its source location.
    pub(super) fn sched_block(&mut self, args: &str, body: &[Line], line: &Line) {
        let opts = match crate::sched::parse_options(args) {
            Ok(opts) => opts,
            Err(message) => return self.diag(Severity::Error, line, 1, message),
        };
        let body = &self.sched_macros(body, 0)[..];
        let texts: Vec<&str> = body.iter().map(|l| l.text.as_str()).collect();
        let resolve = |text: &str| {
            self.get_reg(text, OperandKind::Ra, true)
                .filter(|(_, rest)| rest.trim().is_empty())
                .and_then(|(v, _)| u8::try_from(v).ok())
        };
        let here = self.offsets.get(&self.sect).copied().unwrap_or(0);
        let start = (here + 7) & !7;
        let key: SchedKey = (
            texts.iter().map(|t| t.to_string()).collect(),
            format!("{opts:?}"),
            start,
        );
        let cached = self.schedules.get(&key).filter(|(asked, _)| {
            asked
                .iter()
                .all(|(text, reg)| resolve(text.as_str()) == *reg)
        });
        let result = match cached {
            Some((_, result)) => result.clone(),
            None => {
                let asked = std::cell::RefCell::new(Vec::new());
                let logged = |text: &str| {
                    let reg = resolve(text);
                    asked.borrow_mut().push((text.to_string(), reg));
                    reg
                };
                let result = crate::sched::schedule(&texts, &opts, Some(start), &logged);
                self.schedules
                    .insert(key, (asked.into_inner(), result.clone()));
                result
            }
        };
        match result {
            Ok(scheduled) => {
                let lines: Vec<Line> = scheduled
                    .lines
                    .into_iter()
                    .map(|(text, origin)| {
                        let at = origin.and_then(|k| body.get(k)).unwrap_or(line);
                        Line {
                            text,
                            file: at.file.clone(),
                            line: at.line,
                        }
                    })
                    .collect();
                self.run_lines(&lines);
            }
            Err(e) => {
                let at = body.get(e.line).unwrap_or(line);
                self.diag(Severity::Error, at, e.column, e.message);
            }
        }
    }

    /// gas `get_reg`: `$` optional, `chN`/`spN` prefixes for channels and SPRs, decimal
    /// numbers, the names `lr sp rp fp` (or a channel name), else a constant expression
    /// (whose value is ORed in unmasked, as gas does). `None` is a syntax mismatch.
    fn get_reg<'t>(
        &self,
        p: &'t str,
        kind: OperandKind,
        accept_expr: bool,
    ) -> Option<(i64, &'t str)> {
        let mut q = p.strip_prefix('$').unwrap_or(p);
        let b = q.as_bytes();
        let prefixed = |a: u8, c: u8| {
            b.len() > 2
                && b[0].eq_ignore_ascii_case(&a)
                && b[1].eq_ignore_ascii_case(&c)
                && b[2].is_ascii_digit()
        };
        if (kind == OperandKind::Ch && prefixed(b'c', b'h'))
            || (kind == OperandKind::Spr && prefixed(b's', b'p'))
        {
            q = &q[2..];
        }
        let digits = q.bytes().take_while(u8::is_ascii_digit).count();
        if digits > 0 {
            // Any number is a register here; one past 127 is reported as out of range.
            let n: i64 = q[..digits].parse().unwrap_or(i64::MAX);
            return Some((n, &q[digits..]));
        }
        let names: &[(&str, u32)] = match kind {
            OperandKind::Ch => CHANNELS,
            OperandKind::Spr => &[],
            _ => &[("lr", 0), ("sp", 1), ("rp", 0), ("fp", 127)],
        };
        let best = names
            .iter()
            .filter(|(n, _)| {
                q.len() >= n.len()
                    && q.is_char_boundary(n.len())
                    && q[..n.len()].eq_ignore_ascii_case(n)
            })
            .max_by_key(|(n, _)| n.len());
        if let Some((n, v)) = best {
            return Some((*v as i64, &q[n.len()..]));
        }
        if !accept_expr {
            return None;
        }
        match self.eval_prefix(q) {
            Ok((v, rest, undefined, _)) if !v.reloc || (undefined && self.pass == 1) => {
                Some((v.v, rest))
            }
            _ => None,
        }
    }

    /// gas `calcop`: parses `param` as `form`'s operands in order. `Err(None)` is a syntax
    /// mismatch (the next form of the mnemonic is tried); `Err(Some(..))` a hard error.
    fn calcop(&self, form: &FormInfo, param: &str) -> Result<Vec<Operand>, CalcErr> {
        let kinds = form.operands;
        let mut p = param;
        let mut out = Vec::new();
        let at = |p: &str| param.len() - p.len();
        for (i, &kind) in kinds.iter().enumerate() {
            p = p.trim_start();
            if p.is_empty() || p.starts_with(',') {
                return Err(CalcErr::Syntax(i));
            }
            let col = at(p);
            if kind == OperandKind::ParenRa {
                p = p.strip_prefix('(').ok_or(CalcErr::Syntax(i))?.trim_start();
                let (v, rest) = self
                    .get_reg(p, OperandKind::Ra, true)
                    .ok_or(CalcErr::Syntax(i))?;
                if !(0..128).contains(&v) {
                    return Err(CalcErr::Range(
                        at(p),
                        format!("register number {v} out of range [0, 127]"),
                    ));
                }
                p = rest
                    .trim_start()
                    .strip_prefix(')')
                    .ok_or(CalcErr::Syntax(i))?;
                out.push(Operand::Reg(kind, v));
            } else if kind.is_register() {
                let (v, rest) = self.get_reg(p, kind, true).ok_or(CalcErr::Syntax(i))?;
                // gas ORs an expression's value in unmasked; a value outside the 7-bit
                // field would silently change other fields, so it is an error here.
                if !(0..128).contains(&v) {
                    let what = match kind {
                        OperandKind::Ch => "channel",
                        OperandKind::Spr => "special-purpose register",
                        _ => "register",
                    };
                    return Err(CalcErr::Range(
                        col,
                        format!("{what} number {v} out of range [0, 127]"),
                    ));
                }
                p = rest;
                out.push(Operand::Reg(kind, v));
            } else {
                let mut warnings = Vec::new();
                let (mut high, mut low) = (false, false);
                let lower = p.get(..5).unwrap_or(p).to_ascii_lowercase();
                if lower.starts_with("%lo(") {
                    p = &p[3..];
                    low = true;
                    warnings.push(
                        "Using old style, %lo(expr), please change to PPC style, expr@l."
                            .to_string(),
                    );
                } else if lower.starts_with("%hi(") {
                    p = &p[3..];
                    high = true;
                    warnings.push(
                        "Using old style, %hi(expr), please change to PPC style, expr@h."
                            .to_string(),
                    );
                } else if lower.starts_with("%pic(") {
                    p = &p[4..];
                }
                if p.starts_with('$') {
                    if let Some((_, rest)) = self.get_reg(p, kind, false) {
                        let name = &p[..p.len() - rest.len()];
                        warnings.push(format!("Treating '{name}' as a symbol."));
                    }
                }
                if crate::expr::parse(p).is_none() {
                    return Err(CalcErr::Syntax(i));
                }
                let (val, rest, _, w) = self
                    .eval_prefix(p)
                    .map_err(|(c, m)| CalcErr::Hard(at(p) + c, m))?;
                warnings.extend(w);
                p = rest;
                let b = p.as_bytes();
                if b.len() >= 2
                    && b[0] == b'@'
                    && !b
                        .get(2)
                        .is_some_and(|c| c.is_ascii_alphanumeric() || *c == b'@')
                {
                    match b[1] {
                        b'h' | b'H' => {
                            high = true;
                            p = &p[2..];
                        }
                        b'l' | b'L' => {
                            low = true;
                            p = &p[2..];
                        }
                        _ => {}
                    }
                }
                out.push(Operand::Imm {
                    kind,
                    val,
                    high,
                    low,
                    col,
                    warnings,
                });
            }
            p = p.trim_start();
            if i + 1 < kinds.len() && kinds[i + 1] != OperandKind::ParenRa {
                p = p.strip_prefix(',').ok_or(CalcErr::Syntax(i + 1))?;
            }
        }
        if !p.trim().is_empty() {
            return Err(CalcErr::Syntax(kinds.len()));
        }
        Ok(out)
    }

    pub(super) fn instruction(&mut self, mnemonic: &str, args: &str, line: &Line, col: usize) {
        let pc = self.here();
        if mnemonic == "nop" && !split_top(args, ',').iter().skip(1).any(|_| true) {
            // GNU as for SPU reads pseudo-ops without their dot, and `nop` is gas's `.nop`
            // (read.c `s_nop`): its operand is an expression, not a register (`nop $3`
            // names a symbol `$3`, undefined in an object), and no-op words (0x40200000)
            // are written until they cover that many bytes, one at least.
            let mut bytes = 0;
            let operand = args.trim();
            if !operand.is_empty() {
                let c = operand_column(line, operand, col);
                match self.eval_reported(operand, line, c) {
                    Ok(v) if !v.reloc && !v.cross => bytes = v.v.clamp(0, LOCAL_STORE as i64),
                    Ok(_) => {}
                    Err((at, m)) if self.object => self.diag(Severity::Error, line, c + at, m),
                    Err(_) => {}
                }
            }
            let start = self.here() as i64;
            loop {
                let before = self.here();
                self.emit(&0x4020_0000u32.to_be_bytes());
                // Past the local store the place stops moving (the size check reports it).
                if self.here() as i64 - start >= bytes || self.here() == before {
                    return;
                }
            }
        }
        let forms: Vec<&'static FormInfo> = forms_named(mnemonic).collect();
        if forms.is_empty() {
            self.diag(
                Severity::Error,
                line,
                col,
                format!("Invalid mnemonic '{mnemonic}'"),
            );
            self.emit(&[0; 4]);
            return;
        }
        if let Some(ext) = forms[0].op.info().ext {
            if !self.extensions.enables(ext) {
                let name = ext.name();
                self.diag(
                    Severity::Error,
                    line,
                    col,
                    format!("'{mnemonic}' is an instruction of the {name} extension, which is off (`.spu_ext {name}` or `--ext {name}` turns it on)"),
                );
                self.emit(&[0; 4]);
                return;
            }
        }
        let arg_col = line
            .text
            .find(args.trim())
            .filter(|_| !args.trim().is_empty())
            .map(|p| p + 1)
            .unwrap_or(col);
        let param = args.trim();
        let mut failure = (forms[0], 0);
        let mut range_failure: Option<(usize, String)> = None;
        let mut parsed = None;
        for form in &forms {
            match self.calcop(form, param) {
                Ok(ops) => {
                    parsed = Some((*form, ops));
                    break;
                }
                Err(CalcErr::Syntax(arg)) => failure = (form, arg),
                // Another form may take this operand as something else (`hgti $3,-16`
                // is the two-operand form); reported only if no form fits.
                Err(CalcErr::Range(c, m)) => {
                    range_failure.get_or_insert((c, m));
                }
                Err(CalcErr::Hard(c, m)) => {
                    self.diag(Severity::Error, line, arg_col + c, m);
                    self.emit(&[0; 4]);
                    return;
                }
            }
        }
        let Some((form, ops)) = parsed else {
            if let Some((c, m)) = range_failure {
                self.diag(Severity::Error, line, arg_col + c, m);
                self.emit(&[0; 4]);
                return;
            }
            let (form, arg) = failure;
            self.diag(
                Severity::Error,
                line,
                arg_col,
                format!(
                    "Error in argument {}.  Expecting:  \"{}\"",
                    arg + 1,
                    insn_fmt_string(form, arg)
                ),
            );
            self.emit(&[0; 4]);
            return;
        };
        let mut word = form.base_word();
        for op in ops {
            match op {
                Operand::Reg(kind, v) => {
                    let pos = match kind {
                        OperandKind::Rt if form.format == Format::RRR => 21,
                        OperandKind::Rt | OperandKind::Rc => 0,
                        OperandKind::Rb => 14,
                        _ => 7,
                    };
                    word |= (v as u32).wrapping_shl(pos);
                }
                Operand::Imm {
                    kind,
                    val,
                    high,
                    low,
                    col: c,
                    warnings,
                } => {
                    if self.pass == 2 {
                        for w in warnings {
                            self.diag(Severity::Warning, line, arg_col + c, w);
                        }
                    }
                    if self.object && self.pass == 2 && (val.reloc || val.cross) {
                        let call = mnemonic.eq_ignore_ascii_case("brsl")
                            || mnemonic.eq_ignore_ascii_case("brasl");
                        let jump = mnemonic.eq_ignore_ascii_case("br")
                            || mnemonic.eq_ignore_ascii_case("bra");
                        let branch = (call, jump);
                        match self.object_immediate(form.format, kind, val, high, low, pc, branch) {
                            Ok(Some(bits)) => word |= bits,
                            Ok(None) => {
                                let sect = self.sect;
                                let at = pc - self.section_start(sect) as u32;
                                let rk = reloc_kind(kind, form.format, high, low);
                                match (rk, self.pending.take()) {
                                    (Some(rk), Some(v)) => {
                                        self.add_reloc(sect, at, rk, &v, line, arg_col + c)
                                    }
                                    _ => self.diag(
                                        Severity::Error,
                                        line,
                                        arg_col + c,
                                        "no SPU relocation for this operand",
                                    ),
                                }
                            }
                            Err(m) => self.diag(Severity::Error, line, arg_col + c, m),
                        }
                        continue;
                    }
                    match self.immediate(form.format, kind, val, high, low, pc) {
                        Ok((bits, warning)) => {
                            word |= bits;
                            if let Some(w) = warning {
                                self.diag(Severity::Warning, line, arg_col + c, w);
                            }
                        }
                        Err(m) => self.diag(Severity::Error, line, arg_col + c, m),
                    }
                }
            }
        }
        self.emit(&word.to_be_bytes());
    }

    /// An operand that depends on an address, in an object: a PC-relative reference to a
    /// local symbol of this very section is resolved now (as gas's `fixup_segment` does);
    /// anything else is left in `pending` for a relocation. `(call, jump)`: the instruction
    /// is `brsl`/`brasl`, or `br`/`bra`.
    #[allow(clippy::too_many_arguments)]
    fn object_immediate(
        &mut self,
        format: Format,
        kind: OperandKind,
        val: Val,
        high: bool,
        low: bool,
        pc: u32,
        (call, jump): (bool, bool),
    ) -> Result<Option<u32>, String> {
        let pcrel = matches!(kind, OperandKind::Rel18 | OperandKind::BrInst);
        let here = self.chunks[self.sect].0;
        let attrs = val.sym.as_ref().and_then(|(n, _)| self.attrs.get(&**n));
        let global = attrs.is_some_and(|a| a.global || a.weak);
        let function = attrs.is_some_and(|a| a.kind == super::symbols::STT_FUNC);
        if val.cross || (val.sect.is_none() && val.sym.is_none()) {
            return Err("expression too complex for a relocation".into());
        }
        // Only references to local symbols are resolved: gas leaves a relocation for a
        // global or weak symbol even in the same section (checked with spu-elf-as 2.40),
        // and tc-spu.h's `TC_FORCE_RELOCATION` keeps every call's (`brsl`, `brasl`) and a
        // jump's (`br`, `bra`) to a function: tail and sibling calls, for overlay stubs.
        let forced = call || (jump && function);
        if pcrel && val.sect == Some(here) && !global && !forced && !high && !low {
            let local = Val { sym: None, ..val };
            return self
                .immediate(format, kind, local, false, false, pc)
                .map(|(bits, _)| Some(bits));
        }
        self.pending = Some(val);
        Ok(None)
    }

    /// The bits an immediate operand contributes, as gas's `get_imm` (constants) and
    /// `md_apply_fix` (values that depend on addresses) compute them, with the range
    /// error or warning gas gives.
    fn immediate(
        &self,
        format: Format,
        kind: OperandKind,
        val: Val,
        high: bool,
        low: bool,
        pc: u32,
    ) -> Result<(u32, Option<String>), String> {
        use OperandKind::*;
        let enc = arg_encode(kind);
        if self.pass == 1 {
            return Ok((0, None));
        }
        if !val.reloc {
            // A constant: gas keeps it in an `int`, then applies @h/@l, checks, encodes.
            let mut v = val.v as i32 as i64;
            if high {
                v >>= 16;
            } else if low {
                v &= 0xffff;
            }
            let mut warning = None;
            if enc.hi > enc.lo && (v < enc.lo || v > enc.hi) {
                return Err(format!(
                    "Constant expression {v} out of range, [{}, {}].",
                    enc.lo, enc.hi
                ));
            } else if enc.whi > enc.wlo && (v < enc.wlo || v > enc.whi) {
                warning = Some(format!(
                    "Constant expression {v} out of range, [{}, {}].",
                    enc.wlo, enc.whi
                ));
            }
            match kind {
                Scale173 => v = 173 - v,
                Scale155 => v = 155 - v,
                _ => {}
            }
            let mut bits = 0u32;
            if kind == BrInst {
                bits |= ((v >> 2) & 0x7f) as u32;
            }
            let pos = if kind == BrInst && format == Format::LBTI {
                14
            } else {
                enc.pos
            };
            bits |= (((v >> enc.rshift) & ((1i64 << enc.size) - 1)) as u32) << pos;
            return Ok((bits, warning));
        }
        // An address: resolved here as the linker would (PC-relative kinds against this
        // instruction's address).
        let pcrel = matches!(kind, Rel18 | BrInst);
        let v = if pcrel { val.v - pc as i64 } else { val.v };
        if high {
            return Ok(((((v >> 16) & 0xffff) as u32) << 7, None));
        }
        if low {
            return Ok((((v & 0xffff) as u32) << 7, None));
        }
        if enc.hi > enc.lo && (v < enc.lo || v > enc.hi) {
            return Err(format!(
                "Relocation doesn't fit. (relocation value = 0x{:x})",
                v
            ));
        }
        let bits = match kind {
            BrInst if format == Format::LBTI => ((v & 0x1fc) >> 2) | ((v & 0x600) << 5),
            BrInst => ((v & 0x1fc) >> 2) | ((v & 0x600) << 14),
            U14 => v & 0x3fff,
            _ => ((v >> enc.rshift) & ((1i64 << enc.size) - 1)) << enc.pos,
        };
        Ok((bits as u32, None))
    }
}

/// The SPU relocation gas's `arg_encode` table gives an immediate operand.
fn reloc_kind(kind: OperandKind, format: Format, high: bool, low: bool) -> Option<u32> {
    use crate::reloc::*;
    use OperandKind::*;
    if high {
        return Some(R_SPU_ADDR16_HI);
    }
    if low {
        return Some(R_SPU_ADDR16_LO);
    }
    Some(match kind {
        S3 | S6 | S7 | S7n | U3 | U5 | U6 | U7 => R_SPU_ADDR7,
        S10b | S10 => R_SPU_ADDR10I,
        Off14 => R_SPU_ADDR10,
        S16 | X16 => R_SPU_ADDR16I,
        Abs18 => R_SPU_ADDR16,
        Rel18 => R_SPU_REL16,
        U18 => R_SPU_ADDR18,
        BrInst if format == Format::LBTI => R_SPU_REL9I,
        BrInst => R_SPU_REL9,
        _ => return None,
    })
}

/// Padding of `pad` bytes from address `at` in code (tc-spu.c `spu_handle_align`): zero
/// bytes to a word, then lnop in an odd slot, then nop/lnop pairs.
pub(super) fn code_padding(at: u32, pad: u32) -> Vec<u8> {
    let mut bytes = Vec::new();
    let mut left = pad;
    let mut pos = at;
    while left & 3 != 0 {
        bytes.push(0);
        left -= 1;
        pos += 1;
    }
    while left > 0 {
        let word: u32 = if pos & 4 != 0 {
            0x0020_0000
        } else {
            0x4020_0000
        };
        bytes.extend(word.to_be_bytes());
        left -= 4;
        pos += 4;
    }
    bytes
}
