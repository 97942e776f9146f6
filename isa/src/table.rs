//! The one declaration of every SPU instruction and its assembler forms.
//!
//! Everything about an instruction — its opcode, format, operand order, pipe and latency,
//! the assembler forms that produce it — is written once, in [`for_each_op!`](crate::for_each_op). The
//! encoder, the decoder table, the disassembler, the visitor used by the interpreter and
//! the profilers, and the timing classes are all derived from it (the pattern of
//! wasmtime's Pulley `for_each_op!`). Rows follow the order of the GNU binutils SPU opcode
//! table, because the disassembler prints the first form listed for an encoding.
//!
//! Row syntax: `Variant snake FORMAT opcode11 UNIT { forms } [@Extension]`; each form is
//! `"mnemonic" [+extra_bits] [as FORMAT] [operand kinds] [= "alias_of"]`. A row tagged
//! `@Extension` is an instruction of one of the paper's proposed extensions
//! ([`crate::ext`]), in encoding space the real SPU leaves unused; it decodes only where
//! that extension is on. Those rows come last, after the binutils table.

use crate::ext::Extension;

/// Calls `$cb!` with the whole instruction table (see the module docs for the syntax).
#[macro_export]
macro_rules! for_each_op {
    ($cb:ident) => {
        $cb! {
        Br        br        RI16 0x190 BR   { "br" [Rel18] }
        Brsl      brsl      RI16 0x198 BR   { "brsl" [Rt, Rel18] }
        Bra       bra       RI16 0x180 BR   { "bra" [Abs18] }
        Brasl     brasl     RI16 0x188 BR   { "brasl" [Rt, Abs18] }
        Fsmbi     fsmbi     RI16 0x194 SHUF { "fsmbi" [Rt, X16] }
        Lqa       lqa       RI16 0x184 LS   { "lqa" [Rt, Abs18] }
        Lqr       lqr       RI16 0x19c LS   { "lqr" [Rt, Rel18] }
        Stop      stop      RR   0x000 BR   { "stop" [], "stop" [U14] }
        Stopd     stopd     RR   0x140 BR   { "stopd" [Rt, Ra, Rb] }
        Lnop      lnop      RR   0x001 LNOP { "lnop" [] }
        Sync      sync      RR   0x002 BR   { "sync" [], "syncc" +0x40 [] }
        Dsync     dsync     RR   0x003 BR   { "dsync" [] }
        Mfspr     mfspr     RR   0x00c SPR  { "mfspr" [Rt, Spr] }
        Rdch      rdch      RR   0x00d SPR  { "rdch" [Rt, Ch] }
        Rchcnt    rchcnt    RR   0x00f SPR  { "rchcnt" [Rt, Ch] }
        Hbra      hbra      LBT  0x080 LS   { "hbra" [BrInst, Abs18] }
        Hbrr      hbrr      LBT  0x090 LS   { "hbrr" [BrInst, Rel18] }
        Brz       brz       RI16 0x100 BR   { "brz" [Rt, Rel18] }
        Brnz      brnz      RI16 0x108 BR   { "brnz" [Rt, Rel18] }
        Brhz      brhz      RI16 0x110 BR   { "brhz" [Rt, Rel18] }
        Brhnz     brhnz     RI16 0x118 BR   { "brhnz" [Rt, Rel18] }
        Stqa      stqa      RI16 0x104 LS   { "stqa" [Rt, Abs18] }
        Stqr      stqr      RI16 0x11c LS   { "stqr" [Rt, Rel18] }
        Mtspr     mtspr     RR   0x10c SPR  { "mtspr" [Spr, Rt], "syscall" as RI7 [Rt, Ra, S7n] = "mtspr" }
        Wrch      wrch      RR   0x10d SPR  { "wrch" [Ch, Rt] }
        Lqd       lqd       RI10 0x1a0 LS   { "lqd" [Rt, Off14, ParenRa] }
        Bi        bi        RR   0x1a8 BR   { "bi" [Ra], "bid" +0x20 [Ra], "bie" +0x10 [Ra] }
        Bisl      bisl      RR   0x1a9 BR   { "bisl" [Rt, Ra], "bisld" +0x20 [Rt, Ra], "bisle" +0x10 [Rt, Ra] }
        Iret      iret      RR   0x1aa BR   { "iret" [Ra], "iret" [], "iretd" +0x20 [Ra], "iretd" +0x20 [], "irete" +0x10 [Ra], "irete" +0x10 [] }
        Bisled    bisled    RR   0x1ab BR   { "bisled" [Rt, Ra], "bisledd" +0x20 [Rt, Ra], "bislede" +0x10 [Rt, Ra] }
        Hbr       hbr       LBTI 0x1ac LS   { "hbr" [BrInst, Ra], "hbrp" +0x40 [] }
        Frest     frest     RR   0x1b8 SHUF { "frest" [Rt, Ra] }
        Frsqest   frsqest   RR   0x1b9 SHUF { "frsqest" [Rt, Ra] }
        Fsm       fsm       RR   0x1b4 SHUF { "fsm" [Rt, Ra] }
        Fsmh      fsmh      RR   0x1b5 SHUF { "fsmh" [Rt, Ra] }
        Fsmb      fsmb      RR   0x1b6 SHUF { "fsmb" [Rt, Ra] }
        Gb        gb        RR   0x1b0 SHUF { "gb" [Rt, Ra] }
        Gbh       gbh       RR   0x1b1 SHUF { "gbh" [Rt, Ra] }
        Gbb       gbb       RR   0x1b2 SHUF { "gbb" [Rt, Ra] }
        Cbd       cbd       RI7  0x1f4 SHUF { "cbd" [Rt, U7, ParenRa] }
        Chd       chd       RI7  0x1f5 SHUF { "chd" [Rt, U7, ParenRa] }
        Cwd       cwd       RI7  0x1f6 SHUF { "cwd" [Rt, U7, ParenRa] }
        Cdd       cdd       RI7  0x1f7 SHUF { "cdd" [Rt, U7, ParenRa] }
        Rotqbii   rotqbii   RI7  0x1f8 SHUF { "rotqbii" [Rt, Ra, U3] }
        Rotqbyi   rotqbyi   RI7  0x1fc SHUF { "rotqbyi" [Rt, Ra, S7n] }
        Rotqmbii  rotqmbii  RI7  0x1f9 SHUF { "rotqmbii" [Rt, Ra, S3] }
        Rotqmbyi  rotqmbyi  RI7  0x1fd SHUF { "rotqmbyi" [Rt, Ra, S6] }
        Shlqbii   shlqbii   RI7  0x1fb SHUF { "shlqbii" [Rt, Ra, U3] }
        Shlqbyi   shlqbyi   RI7  0x1ff SHUF { "shlqbyi" [Rt, Ra, U5] }
        Stqd      stqd      RI10 0x120 LS   { "stqd" [Rt, Off14, ParenRa] }
        Bihnz     bihnz     RR   0x12b BR   { "bihnz" [Rt, Ra], "bihnzd" +0x20 [Rt, Ra], "bihnze" +0x10 [Rt, Ra], "biht" [Rt, Ra] = "bihnz", "bihtd" +0x20 [Rt, Ra] = "bihnzd", "bihte" +0x10 [Rt, Ra] = "bihnze" }
        Bihz      bihz      RR   0x12a BR   { "bihz" [Rt, Ra], "bihzd" +0x20 [Rt, Ra], "bihze" +0x10 [Rt, Ra], "bihf" [Rt, Ra] = "bihz", "bihfd" +0x20 [Rt, Ra] = "bihzd", "bihfe" +0x10 [Rt, Ra] = "bihze" }
        Binz      binz      RR   0x129 BR   { "binz" [Rt, Ra], "binzd" +0x20 [Rt, Ra], "binze" +0x10 [Rt, Ra], "bit" [Rt, Ra] = "binz", "bitd" +0x20 [Rt, Ra] = "binzd", "bite" +0x10 [Rt, Ra] = "binze" }
        Biz       biz       RR   0x128 BR   { "biz" [Rt, Ra], "bizd" +0x20 [Rt, Ra], "bize" +0x10 [Rt, Ra], "bif" [Rt, Ra] = "biz", "bifd" +0x20 [Rt, Ra] = "bizd", "bife" +0x10 [Rt, Ra] = "bize" }
        Cbx       cbx       RR   0x1d4 SHUF { "cbx" [Rt, Ra, Rb] }
        Chx       chx       RR   0x1d5 SHUF { "chx" [Rt, Ra, Rb] }
        Cwx       cwx       RR   0x1d6 SHUF { "cwx" [Rt, Ra, Rb] }
        Cdx       cdx       RR   0x1d7 SHUF { "cdx" [Rt, Ra, Rb] }
        Lqx       lqx       RR   0x1c4 LS   { "lqx" [Rt, Ra, Rb] }
        Rotqbi    rotqbi    RR   0x1d8 SHUF { "rotqbi" [Rt, Ra, Rb] }
        Rotqmbi   rotqmbi   RR   0x1d9 SHUF { "rotqmbi" [Rt, Ra, Rb] }
        Shlqbi    shlqbi    RR   0x1db SHUF { "shlqbi" [Rt, Ra, Rb] }
        Rotqby    rotqby    RR   0x1dc SHUF { "rotqby" [Rt, Ra, Rb] }
        Rotqmby   rotqmby   RR   0x1dd SHUF { "rotqmby" [Rt, Ra, Rb] }
        Shlqby    shlqby    RR   0x1df SHUF { "shlqby" [Rt, Ra, Rb] }
        Rotqbybi  rotqbybi  RR   0x1cc SHUF { "rotqbybi" [Rt, Ra, Rb] }
        Rotqmbybi rotqmbybi RR   0x1cd SHUF { "rotqmbybi" [Rt, Ra, Rb] }
        Shlqbybi  shlqbybi  RR   0x1cf SHUF { "shlqbybi" [Rt, Ra, Rb] }
        Stqx      stqx      RR   0x144 LS   { "stqx" [Rt, Ra, Rb] }
        Shufb     shufb     RRR  0x580 SHUF { "shufb" [Rt, Ra, Rb, Rc] }
        Il        il        RI16 0x204 FX2  { "il" [Rt, S16] }
        Ilh       ilh       RI16 0x20c FX2  { "ilh" [Rt, X16] }
        Ilhu      ilhu      RI16 0x208 FX2  { "ilhu" [Rt, X16] }
        Ila       ila       RI18 0x210 FX2  { "ila" [Rt, U18] }
        Nop       nop       RR   0x201 NOP  { "nop" [Rt], "nop" [] }
        Iohl      iohl      RI16 0x304 FX2  { "iohl" [Rt, X16] }
        Andbi     andbi     RI10 0x0b0 FX2  { "andbi" [Rt, Ra, S10b] }
        Andhi     andhi     RI10 0x0a8 FX2  { "andhi" [Rt, Ra, S10] }
        Andi      andi      RI10 0x0a0 FX2  { "andi" [Rt, Ra, S10] }
        Orbi      orbi      RI10 0x030 FX2  { "orbi" [Rt, Ra, S10b] }
        Orhi      orhi      RI10 0x028 FX2  { "orhi" [Rt, Ra, S10] }
        Ori       ori       RI10 0x020 FX2  { "ori" [Rt, Ra, S10], "lr" [Rt, Ra] = "ori" }
        Orx       orx       RR   0x1f0 BR   { "orx" [Rt, Ra] }
        Xorbi     xorbi     RI10 0x230 FX2  { "xorbi" [Rt, Ra, S10b] }
        Xorhi     xorhi     RI10 0x228 FX2  { "xorhi" [Rt, Ra, S10] }
        Xori      xori      RI10 0x220 FX2  { "xori" [Rt, Ra, S10] }
        Ahi       ahi       RI10 0x0e8 FX2  { "ahi" [Rt, Ra, S10] }
        Ai        ai        RI10 0x0e0 FX2  { "ai" [Rt, Ra, S10] }
        Sfhi      sfhi      RI10 0x068 FX2  { "sfhi" [Rt, Ra, S10] }
        Sfi       sfi       RI10 0x060 FX2  { "sfi" [Rt, Ra, S10] }
        Cgtbi     cgtbi     RI10 0x270 FX2  { "cgtbi" [Rt, Ra, S10b] }
        Cgthi     cgthi     RI10 0x268 FX2  { "cgthi" [Rt, Ra, S10] }
        Cgti      cgti      RI10 0x260 FX2  { "cgti" [Rt, Ra, S10] }
        Clgtbi    clgtbi    RI10 0x2f0 FX2  { "clgtbi" [Rt, Ra, S10b] }
        Clgthi    clgthi    RI10 0x2e8 FX2  { "clgthi" [Rt, Ra, S10] }
        Clgti     clgti     RI10 0x2e0 FX2  { "clgti" [Rt, Ra, S10] }
        Ceqbi     ceqbi     RI10 0x3f0 FX2  { "ceqbi" [Rt, Ra, S10b] }
        Ceqhi     ceqhi     RI10 0x3e8 FX2  { "ceqhi" [Rt, Ra, S10] }
        Ceqi      ceqi      RI10 0x3e0 FX2  { "ceqi" [Rt, Ra, S10] }
        Hgti      hgti      RI10 0x278 FX2  { "hgti" [Rt, Ra, S10], "hgti" [Ra, S10] }
        Hlgti     hlgti     RI10 0x2f8 FX2  { "hlgti" [Rt, Ra, S10], "hlgti" [Ra, S10] }
        Heqi      heqi      RI10 0x3f8 FX2  { "heqi" [Rt, Ra, S10], "heqi" [Ra, S10] }
        Mpyi      mpyi      RI10 0x3a0 FP7  { "mpyi" [Rt, Ra, S10] }
        Mpyui     mpyui     RI10 0x3a8 FP7  { "mpyui" [Rt, Ra, S10] }
        Cflts     cflts     RI8  0x3b0 FP7  { "cflts" [Rt, Ra, Scale173] }
        Cfltu     cfltu     RI8  0x3b2 FP7  { "cfltu" [Rt, Ra, Scale173] }
        Csflt     csflt     RI8  0x3b4 FP7  { "csflt" [Rt, Ra, Scale155] }
        Cuflt     cuflt     RI8  0x3b6 FP7  { "cuflt" [Rt, Ra, Scale155] }
        Fesd      fesd      RR   0x3b8 FPD  { "fesd" [Rt, Ra] }
        Frds      frds      RR   0x3b9 FPD  { "frds" [Rt, Ra] }
        Fscrrd    fscrrd    RR   0x398 FPD  { "fscrrd" [Rt] }
        Fscrwr    fscrwr    RR   0x3ba FP7  { "fscrwr" [Rt, Ra], "fscrwr" [Ra] }
        Clz       clz       RR   0x2a5 FX2  { "clz" [Rt, Ra] }
        Cntb      cntb      RR   0x2b4 FXB  { "cntb" [Rt, Ra] }
        Xsbh      xsbh      RR   0x2b6 FX2  { "xsbh" [Rt, Ra] }
        Xshw      xshw      RR   0x2ae FX2  { "xshw" [Rt, Ra] }
        Xswd      xswd      RR   0x2a6 FX2  { "xswd" [Rt, Ra] }
        Roti      roti      RI7  0x078 FX3  { "roti" [Rt, Ra, S7n] }
        Rotmi     rotmi     RI7  0x079 FX3  { "rotmi" [Rt, Ra, S7] }
        Rotmai    rotmai    RI7  0x07a FX3  { "rotmai" [Rt, Ra, S7] }
        Shli      shli      RI7  0x07b FX3  { "shli" [Rt, Ra, U6] }
        Rothi     rothi     RI7  0x07c FX3  { "rothi" [Rt, Ra, S7n] }
        Rothmi    rothmi    RI7  0x07d FX3  { "rothmi" [Rt, Ra, S6] }
        Rotmahi   rotmahi   RI7  0x07e FX3  { "rotmahi" [Rt, Ra, S6] }
        Shlhi     shlhi     RI7  0x07f FX3  { "shlhi" [Rt, Ra, U5] }
        A         a         RR   0x0c0 FX2  { "a" [Rt, Ra, Rb] }
        Ah        ah        RR   0x0c8 FX2  { "ah" [Rt, Ra, Rb] }
        Sf        sf        RR   0x040 FX2  { "sf" [Rt, Ra, Rb] }
        Sfh       sfh       RR   0x048 FX2  { "sfh" [Rt, Ra, Rb] }
        Cgt       cgt       RR   0x240 FX2  { "cgt" [Rt, Ra, Rb] }
        Cgtb      cgtb      RR   0x250 FX2  { "cgtb" [Rt, Ra, Rb] }
        Cgth      cgth      RR   0x248 FX2  { "cgth" [Rt, Ra, Rb] }
        Clgt      clgt      RR   0x2c0 FX2  { "clgt" [Rt, Ra, Rb] }
        Clgtb     clgtb     RR   0x2d0 FX2  { "clgtb" [Rt, Ra, Rb] }
        Clgth     clgth     RR   0x2c8 FX2  { "clgth" [Rt, Ra, Rb] }
        Ceq       ceq       RR   0x3c0 FX2  { "ceq" [Rt, Ra, Rb] }
        Ceqb      ceqb      RR   0x3d0 FX2  { "ceqb" [Rt, Ra, Rb] }
        Ceqh      ceqh      RR   0x3c8 FX2  { "ceqh" [Rt, Ra, Rb] }
        Hgt       hgt       RR   0x258 FX2  { "hgt" [Rt, Ra, Rb], "hgt" [Ra, Rb] }
        Hlgt      hlgt      RR   0x2d8 FX2  { "hlgt" [Rt, Ra, Rb], "hlgt" [Ra, Rb] }
        Heq       heq       RR   0x3d8 FX2  { "heq" [Rt, Ra, Rb], "heq" [Ra, Rb] }
        Fceq      fceq      RR   0x3c2 FX2  { "fceq" [Rt, Ra, Rb] }
        Fcmeq     fcmeq     RR   0x3ca FX2  { "fcmeq" [Rt, Ra, Rb] }
        Fcgt      fcgt      RR   0x2c2 FX2  { "fcgt" [Rt, Ra, Rb] }
        Fcmgt     fcmgt     RR   0x2ca FX2  { "fcmgt" [Rt, Ra, Rb] }
        And       and       RR   0x0c1 FX2  { "and" [Rt, Ra, Rb] }
        Nand      nand      RR   0x0c9 FX2  { "nand" [Rt, Ra, Rb] }
        Or        or        RR   0x041 FX2  { "or" [Rt, Ra, Rb] }
        Nor       nor       RR   0x049 FX2  { "nor" [Rt, Ra, Rb] }
        Xor       xor       RR   0x241 FX2  { "xor" [Rt, Ra, Rb] }
        Eqv       eqv       RR   0x249 FX2  { "eqv" [Rt, Ra, Rb] }
        Andc      andc      RR   0x2c1 FX2  { "andc" [Rt, Ra, Rb] }
        Orc       orc       RR   0x2c9 FX2  { "orc" [Rt, Ra, Rb] }
        Absdb     absdb     RR   0x053 FXB  { "absdb" [Rt, Ra, Rb] }
        Avgb      avgb      RR   0x0d3 FXB  { "avgb" [Rt, Ra, Rb] }
        Sumb      sumb      RR   0x253 FXB  { "sumb" [Rt, Ra, Rb] }
        Dfa       dfa       RR   0x2cc FPD  { "dfa" [Rt, Ra, Rb] }
        Dfm       dfm       RR   0x2ce FPD  { "dfm" [Rt, Ra, Rb] }
        Dfs       dfs       RR   0x2cd FPD  { "dfs" [Rt, Ra, Rb] }
        Fa        fa        RR   0x2c4 FP6  { "fa" [Rt, Ra, Rb] }
        Fm        fm        RR   0x2c6 FP6  { "fm" [Rt, Ra, Rb] }
        Fs        fs        RR   0x2c5 FP6  { "fs" [Rt, Ra, Rb] }
        Mpy       mpy       RR   0x3c4 FP7  { "mpy" [Rt, Ra, Rb] }
        Mpyh      mpyh      RR   0x3c5 FP7  { "mpyh" [Rt, Ra, Rb] }
        Mpyhh     mpyhh     RR   0x3c6 FP7  { "mpyhh" [Rt, Ra, Rb] }
        Mpyhhu    mpyhhu    RR   0x3ce FP7  { "mpyhhu" [Rt, Ra, Rb] }
        Mpys      mpys      RR   0x3c7 FP7  { "mpys" [Rt, Ra, Rb] }
        Mpyu      mpyu      RR   0x3cc FP7  { "mpyu" [Rt, Ra, Rb] }
        Fi        fi        RR   0x3d4 FP7  { "fi" [Rt, Ra, Rb] }
        Rot       rot       RR   0x058 FX3  { "rot" [Rt, Ra, Rb] }
        Rotm      rotm      RR   0x059 FX3  { "rotm" [Rt, Ra, Rb] }
        Rotma     rotma     RR   0x05a FX3  { "rotma" [Rt, Ra, Rb] }
        Shl       shl       RR   0x05b FX3  { "shl" [Rt, Ra, Rb] }
        Roth      roth      RR   0x05c FX3  { "roth" [Rt, Ra, Rb] }
        Rothm     rothm     RR   0x05d FX3  { "rothm" [Rt, Ra, Rb] }
        Rotmah    rotmah    RR   0x05e FX3  { "rotmah" [Rt, Ra, Rb] }
        Shlh      shlh      RR   0x05f FX3  { "shlh" [Rt, Ra, Rb] }
        Mpyhha    mpyhha    RR   0x346 FP7  { "mpyhha" [Rt, Ra, Rb] }
        Mpyhhau   mpyhhau   RR   0x34e FP7  { "mpyhhau" [Rt, Ra, Rb] }
        Dfma      dfma      RR   0x35c FPD  { "dfma" [Rt, Ra, Rb] }
        Dfms      dfms      RR   0x35d FPD  { "dfms" [Rt, Ra, Rb] }
        Dfnms     dfnms     RR   0x35e FPD  { "dfnms" [Rt, Ra, Rb] }
        Dfnma     dfnma     RR   0x35f FPD  { "dfnma" [Rt, Ra, Rb] }
        Fma       fma       RRR  0x700 FP6  { "fma" [Rt, Ra, Rb, Rc] }
        Fms       fms       RRR  0x780 FP6  { "fms" [Rt, Ra, Rb, Rc] }
        Fnms      fnms      RRR  0x680 FP6  { "fnms" [Rt, Ra, Rb, Rc] }
        Mpya      mpya      RRR  0x600 FP7  { "mpya" [Rt, Ra, Rb, Rc] }
        Selb      selb      RRR  0x400 FX2  { "selb" [Rt, Ra, Rb, Rc] }
        Addx      addx      RR   0x340 FX2  { "addx" [Rt, Ra, Rb] }
        Cg        cg        RR   0x0c2 FX2  { "cg" [Rt, Ra, Rb] }
        Cgx       cgx       RR   0x342 FX2  { "cgx" [Rt, Ra, Rb] }
        Sfx       sfx       RR   0x341 FX2  { "sfx" [Rt, Ra, Rb] }
        Bg        bg        RR   0x042 FX2  { "bg" [Rt, Ra, Rb] }
        Bgx       bgx       RR   0x343 FX2  { "bgx" [Rt, Ra, Rb] }
        Dfceq     dfceq     RR   0x3c3 FX2  { "dfceq" [Rt, Ra, Rb] }
        Dfcmeq    dfcmeq    RR   0x3cb FX2  { "dfcmeq" [Rt, Ra, Rb] }
        Dfcgt     dfcgt     RR   0x2c3 FX2  { "dfcgt" [Rt, Ra, Rb] }
        Dfcmgt    dfcmgt    RR   0x2cb FX2  { "dfcmgt" [Rt, Ra, Rb] }
        Dftsv     dftsv     RI7  0x3bf FX2  { "dftsv" [Rt, Ra, U7] }
        Lgw       lgw       RR   0x1c5 LS   { "lgw" [Rt, Ra] } @Gather
        Lgwx      lgwx      RR   0x1c6 LS   { "lgwx" [Rt, Ra, Rb] } @Gather
        }
    };
}

/// Instruction encoding formats (operand field layouts), as in the SPU ISA.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[allow(clippy::upper_case_acronyms)]
pub enum Format {
    /// Register-register: two source registers `ra`, `rb` and target `rt`, 11-bit opcode.
    RR,
    /// Register-register-register: three sources and a target, 4-bit opcode (`selb`, `fma`, `shufb`).
    RRR,
    /// Register and 7-bit immediate I7 (shift and rotate counts).
    RI7,
    /// Register and 8-bit immediate I8 (the float/integer conversion scales).
    RI8,
    /// Register and 10-bit signed immediate I10 (arithmetic, logical and compare immediates, `lqd`/`stqd`).
    RI10,
    /// 16-bit immediate I16 (immediate loads, relative and absolute branches and loads/stores).
    RI16,
    /// 18-bit immediate I18 (`ila`).
    RI18,
    /// `hbra`/`hbrr`: 16-bit target plus a 9-bit branch offset split over two fields.
    LBT,
    /// `hbr`: register target plus a 9-bit branch offset.
    LBTI,
}

impl Format {
    /// Mask applied to a word's top 11 bits to find the opcode of this format.
    pub const fn opcode_mask(self) -> u16 {
        match self {
            Format::RRR => 0x780,
            Format::RI18 | Format::LBT => 0x7f0,
            Format::RI10 => 0x7f8,
            Format::RI16 => 0x7fc,
            Format::RI8 => 0x7fe,
            Format::RR | Format::RI7 | Format::LBTI => 0x7ff,
        }
    }
}

/// Execution class: decides the pipe and the result latency.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[allow(clippy::upper_case_acronyms)]
pub enum Unit {
    /// Simple fixed-point operations (add, logical, compare), 2 cycles.
    FX2,
    /// Word and halfword rotates and shifts, 4 cycles.
    FX3,
    /// Byte operations (`cntb`, `absdb`, `avgb`, `sumb`), 4 cycles.
    FXB,
    /// Single-precision floating point, 6 cycles.
    FP6,
    /// Integer multiplies, float/integer conversions, `fi` and `fscrwr`, 7 cycles.
    FP7,
    /// Double-precision floating point, 13 cycles (and it blocks issue for a while).
    FPD,
    /// The even pipe's no-op (`nop`), 1 cycle.
    NOP,
    /// Shuffles, quadword shifts and rotates, form-select masks, gathers, insertion controls and the float estimates, 4 cycles.
    SHUF,
    /// Local-store loads and stores, 6 cycles.
    LS,
    /// Branches and branch hints, 4 cycles.
    BR,
    /// Channel and special-purpose register access, 6 cycles.
    SPR,
    /// The odd pipe's no-op (`lnop`), 1 cycle.
    LNOP,
}

/// The SPU's two issue pipes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Pipe {
    /// Pipe 0: fixed-point and floating-point arithmetic.
    Even,
    /// Pipe 1: loads and stores, shuffles, branches and channels.
    Odd,
}

impl Unit {
    /// The pipe this class issues on.
    pub const fn pipe(self) -> Pipe {
        match self {
            Unit::FX2 | Unit::FX3 | Unit::FXB | Unit::FP6 | Unit::FP7 | Unit::FPD | Unit::NOP => {
                Pipe::Even
            }
            Unit::SHUF | Unit::LS | Unit::BR | Unit::SPR | Unit::LNOP => Pipe::Odd,
        }
    }

    /// Cycles from issue until a dependent instruction may issue (`../shared/isa/README.md`).
    pub const fn latency(self) -> u32 {
        match self {
            Unit::FX2 => 2,
            Unit::FX3 | Unit::FXB | Unit::SHUF | Unit::BR => 4,
            Unit::FP6 | Unit::LS | Unit::SPR => 6,
            Unit::FP7 => 7,
            Unit::FPD => 13,
            Unit::NOP | Unit::LNOP => 1,
        }
    }
}

/// How an assembler operand is written and where it goes in the word.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum OperandKind {
    /// Destination register (bits 21..27 in RRR, bits 0..6 otherwise).
    Rt,
    /// First source register (bits 7..13).
    Ra,
    /// Second source register (bits 14..20).
    Rb,
    /// Third source of RRR (bits 0..6).
    Rc,
    /// Channel number in the RA field.
    Ch,
    /// Special-purpose register number in the RA field.
    Spr,
    /// Signed 7-bit immediate in I7.
    S7,
    /// Signed shift or rotate count in I7 that the assembler checks to -32..31 (warning outside -31..0).
    S6,
    /// Signed bit count in I7 for `rotqmbii` (a right shift written as a negative count).
    S3,
    /// Signed 7-bit immediate in I7 used as a rotate count (`roti`, `rotqbyi`).
    S7n,
    /// Unsigned bit count in I7 for the quadword bit rotates and shifts (`rotqbii`, `shlqbii`).
    U3,
    /// Unsigned immediate in I7: the assembler warns above 31 and rejects above 127.
    U5,
    /// Unsigned immediate in I7: the assembler warns above 63 and rejects above 127.
    U6,
    /// Unsigned 7-bit immediate in I7.
    U7,
    /// `cflts`/`cfltu` scale, stored as `173 - scale` in I8.
    Scale173,
    /// `csflt`/`cuflt` scale, stored as `155 - scale` in I8.
    Scale155,
    /// Signed 10-bit immediate in I10.
    S10,
    /// Byte immediate: the low 8 bits matter; outside -128..255 the assembler warns.
    S10b,
    /// `lqd`/`stqd` byte offset, stored divided by 16 in I10.
    Off14,
    /// The base register written in parentheses after an offset: `32($1)`.
    ParenRa,
    /// Signed 16-bit immediate in I16.
    S16,
    /// 16-bit immediate in I16 taken as a bit pattern (signed or unsigned; written in hex by the disassembler).
    X16,
    /// Unsigned 18-bit immediate in I18 (`ila`).
    U18,
    /// Absolute local-store byte address stored divided by 4 in I16.
    Abs18,
    /// PC-relative byte address stored as a word offset in I16.
    Rel18,
    /// Address of the hinted branch, stored as a 9-bit word offset from the hint.
    BrInst,
    /// The 14-bit stop-and-signal code of `stop` (bits 0..13).
    U14,
}

impl OperandKind {
    /// True for operands that name a register-like field (registers, channels, SPRs).
    pub const fn is_register(self) -> bool {
        matches!(
            self,
            OperandKind::Rt
                | OperandKind::Ra
                | OperandKind::Rb
                | OperandKind::Rc
                | OperandKind::ParenRa
                | OperandKind::Ch
                | OperandKind::Spr
        )
    }

    /// True for operands whose value is a local-store address (printed as an address).
    pub const fn is_address(self) -> bool {
        matches!(
            self,
            OperandKind::Abs18 | OperandKind::Rel18 | OperandKind::BrInst
        )
    }
}

/// Static facts about one machine operation (one opcode).
#[derive(Debug)]
pub struct OpInfo {
    /// The operation these facts describe (its index in [`OP_INFO`]).
    pub op: Op,
    /// Canonical mnemonic: the first form binutils lists for this opcode.
    pub name: &'static str,
    /// The operation's encoding format.
    pub format: Format,
    /// The opcode left-justified in 11 bits; the word's base value is `opcode11 << 21`.
    pub opcode11: u16,
    /// The execution class, which decides the pipe and the result latency.
    pub unit: Unit,
    /// The extension this operation belongs to (`None`: the real SPU's).
    pub ext: Option<Extension>,
}

impl OpInfo {
    /// Cycles from issue until a dependent instruction may issue: the unit's latency, but
    /// for the gather loads, whose four local-store reads take [`crate::ext::GATHER_LATENCY`].
    pub const fn latency(&self) -> u32 {
        match self.ext {
            Some(Extension::Gather) => crate::ext::GATHER_LATENCY,
            _ => self.unit.latency(),
        }
    }
}

/// One assembler form: a mnemonic and operand list that encodes to an opcode.
#[derive(Debug)]
pub struct FormInfo {
    /// The mnemonic the assembler accepts and the disassembler may print.
    pub mnemonic: &'static str,
    /// The operation this form encodes to.
    pub op: Op,
    /// The form's field layout (usually the operation's, but `syscall` uses RI7).
    pub format: Format,
    /// Feature bits ORed in at bit 14 (D = 0x20, E = 0x10, `syncc`/`hbrp` 0x40).
    pub extra: u8,
    /// The operands in the order they are written.
    pub operands: &'static [OperandKind],
    /// The mnemonic this one is an alias of (`lr` → `ori`).
    pub alias_of: Option<&'static str>,
}

impl FormInfo {
    /// The word with opcode and feature bits set and every operand field zero.
    pub const fn base_word(&self) -> u32 {
        ((self.op.info().opcode11 as u32) << 21) | ((self.extra as u32) << 14)
    }
}

macro_rules! __opt_str {
    () => {
        None
    };
    ($s:literal) => {
        Some($s)
    };
}

macro_rules! __opt_ext {
    () => {
        None
    };
    ($e:ident) => {
        Some(Extension::$e)
    };
}

macro_rules! __fmt_or {
    ($f:ident) => {
        Format::$f
    };
    ($f:ident $o:ident) => {
        Format::$o
    };
}

macro_rules! define_table {
    ($(
        $Name:ident $snake:ident $fmt:ident $opc:literal $unit:ident {
            $( $mn:literal $(+ $extra:literal)? $(as $ffmt:ident)? [ $($k:ident),* ] $(= $alias:literal)? ),+
        } $(@ $ext:ident)?
    )*) => {
        /// One SPU machine operation (an opcode; feature-bit variants such as `bid` share
        /// the operation of `bi`). `Unknown` stands for a word that matches no opcode.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
        #[repr(u8)]
        pub enum Op {
            $(
                #[doc = concat!("The `", stringify!($snake), "` operation.")]
                $Name,
            )*
            /// A word that matches no opcode (disassembled as `.long`).
            Unknown,
        }

        impl Op {
            /// Every real operation, in table order (without `Unknown`).
            pub const ALL: &'static [Op] = &[$(Op::$Name),*];

            /// Static facts about this operation: its name, format, opcode and unit.
            pub const fn info(self) -> &'static OpInfo { &OP_INFO[self as usize] }
        }

        /// Per-operation facts, indexed by `Op as usize`; the last entry is `Unknown`.
        pub static OP_INFO: &[OpInfo] = &[
            $(OpInfo { op: Op::$Name, name: stringify!($snake), format: Format::$fmt, opcode11: $opc, unit: Unit::$unit, ext: __opt_ext!($($ext)?) },)*
            OpInfo { op: Op::Unknown, name: ".long", format: Format::RR, opcode11: 0, unit: Unit::NOP, ext: None },
        ];

        /// Every assembler form, in binutils table order within each operation.
        pub static FORMS: &[FormInfo] = &[
            $($(
                FormInfo {
                    mnemonic: $mn,
                    op: Op::$Name,
                    format: __fmt_or!($fmt $($ffmt)?),
                    extra: 0 $(| $extra)?,
                    operands: &[$(OperandKind::$k),*],
                    alias_of: __opt_str!($($alias)?),
                },
            )+)*
        ];

        /// One method per operation: the interpreter, the tracer and the profilers
        /// implement this and get the dispatch from [`visit`].
        pub trait Visitor {
            /// The value every visitor method returns.
            type Output;
            $(
                #[doc = concat!("Handles a `", stringify!($snake), "` instruction.")]
                fn $snake(&mut self, inst: $crate::Inst) -> Self::Output;
            )*
            /// Handles a word that decodes to no operation ([`Op::Unknown`]).
            fn unknown(&mut self, inst: $crate::Inst) -> Self::Output;
        }

        /// Dispatches a decoded instruction to the visitor method of its operation.
        #[inline(always)]
        pub fn visit<V: Visitor + ?Sized>(v: &mut V, inst: $crate::Inst) -> V::Output {
            match inst.op {
                $(Op::$Name => v.$snake(inst),)*
                Op::Unknown => v.unknown(inst),
            }
        }
    };
}

for_each_op!(define_table);

/// Number of operations in the table, the extensions' included.
pub const OP_COUNT: usize = Op::ALL.len();

/// The real SPU's operations (the rows without an extension tag), in table order: 199 for
/// the SPU ISA 1.2 as binutils knows it.
pub fn real_ops() -> impl Iterator<Item = Op> {
    Op::ALL.iter().copied().filter(|op| op.info().ext.is_none())
}

/// Looks up every form spelled `mnemonic`, in table order (alternate forms follow).
pub fn forms_named(mnemonic: &str) -> impl Iterator<Item = &'static FormInfo> + '_ {
    // The assembler asks for every instruction it reads: an index by name, made once,
    // rather than a scan of the whole table.
    static BY_NAME: std::sync::OnceLock<
        std::collections::HashMap<&'static str, Vec<&'static FormInfo>>,
    > = std::sync::OnceLock::new();
    let by_name = BY_NAME.get_or_init(|| {
        let mut map = std::collections::HashMap::<_, Vec<_>>::new();
        for f in FORMS {
            map.entry(f.mnemonic).or_default().push(f);
        }
        map
    });
    by_name.get(mnemonic).into_iter().flatten().copied()
}

/// The form the disassembler prints for an operation: its first listed form.
pub fn primary_form(op: Op) -> Option<&'static FormInfo> {
    FORMS.iter().find(|f| f.op == op)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_has_every_opcode_and_form() {
        assert_eq!(real_ops().count(), 199);
        assert_eq!(OP_COUNT, 201);
        assert_eq!(
            FORMS.iter().filter(|f| f.op.info().ext.is_none()).count(),
            243
        );
        assert_eq!(FORMS.len(), 245);
        assert_eq!(OP_INFO.len(), 202);
        // The extension rows come after every real one.
        let first_ext = Op::ALL.iter().position(|op| op.info().ext.is_some());
        assert_eq!(first_ext, Some(199));
        for (i, info) in OP_INFO.iter().enumerate() {
            assert_eq!(info.op as usize, i);
        }
    }

    #[test]
    fn opcodes_are_unique_and_fit_their_format() {
        let mut seen = std::collections::HashSet::new();
        for op in Op::ALL {
            let info = op.info();
            assert!(
                seen.insert(info.opcode11),
                "duplicate opcode {:#x}",
                info.opcode11
            );
            assert_eq!(
                info.opcode11 & !info.format.opcode_mask(),
                0,
                "{}",
                info.name
            );
        }
    }

    #[test]
    fn primary_forms_carry_no_feature_bits() {
        for op in Op::ALL {
            let form = primary_form(*op).unwrap();
            assert_eq!(form.extra, 0, "{}", form.mnemonic);
            assert_eq!(form.mnemonic, op.info().name);
        }
    }

    #[test]
    fn pipes_and_latencies_follow_the_classes() {
        assert_eq!(Op::Fma.info().unit.latency(), 6);
        assert_eq!(Op::Shufb.info().unit.pipe(), Pipe::Odd);
        assert_eq!(Op::Mpy.info().unit.latency(), 7);
        assert_eq!(Op::Dfa.info().unit.latency(), 13);
        assert_eq!(Op::Lqd.info().unit, Unit::LS);
        assert_eq!(Op::Orx.info().unit.pipe(), Pipe::Odd);
    }
}
