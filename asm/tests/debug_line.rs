//! `.file`/`.loc` and the `.debug_line` an object gets from them (GNU as 2.40's
//! dwarf2dbg.c for spu-elf: version 3, minimum instruction length 1, line_base -5,
//! line_range 14, opcode_base 13). Each table is decoded here by a line-program reader
//! written from the DWARF 3 specification (section 6.2), so the tests assert the rows
//! the bytes mean, and for small cases the exact bytes as hand-encoded.

use spu_asm::link::{link, LinkOptions};
use spu_asm::object::Object;
use spu_asm::reloc::R_SPU_ADDR32;
use spu_asm::{assemble, assemble_object, Options, RelocTarget, Severity};

fn object(src: &str) -> Object {
    let (obj, warnings) = assemble_object(src, "t.s", &Options::default()).unwrap_or_else(|e| {
        panic!(
            "{}",
            e.iter()
                .map(|d| d.to_string())
                .collect::<Vec<_>>()
                .join("\n")
        )
    });
    assert!(warnings.is_empty(), "{warnings:?}");
    let back = Object::from_elf("t.o", &obj.to_elf().unwrap()).unwrap();
    assert_eq!(back.sections, obj.sections);
    back
}

/// One row of the line-number matrix.
#[derive(Clone, Debug, PartialEq, Eq)]
struct Row {
    address: u32,
    file: u32,
    line: u32,
    column: u32,
    is_stmt: bool,
    basic_block: bool,
    end_sequence: bool,
    prologue_end: bool,
    epilogue_begin: bool,
    isa: u32,
    discriminator: u32,
}

/// A row with the defaults of a new sequence at `address`, then adjusted.
fn row(address: u32, file: u32, line: u32, column: u32) -> Row {
    Row {
        address,
        file,
        line,
        column,
        is_stmt: true,
        basic_block: false,
        end_sequence: false,
        prologue_end: false,
        epilogue_begin: false,
        isa: 0,
        discriminator: 0,
    }
}

fn end(address: u32, last: &Row) -> Row {
    Row {
        address,
        end_sequence: true,
        basic_block: false,
        prologue_end: false,
        epilogue_begin: false,
        discriminator: 0,
        ..last.clone()
    }
}

/// The decoded table: include directories, files (name, directory), rows.
#[derive(Debug)]
struct Table {
    dirs: Vec<String>,
    files: Vec<(String, u64)>,
    rows: Vec<Row>,
}

fn uleb(b: &[u8], at: &mut usize) -> u64 {
    let (mut v, mut shift) = (0u64, 0);
    loop {
        let byte = b[*at];
        *at += 1;
        v |= ((byte & 0x7f) as u64) << shift;
        shift += 7;
        if byte & 0x80 == 0 {
            return v;
        }
    }
}

fn sleb(b: &[u8], at: &mut usize) -> i64 {
    let (mut v, mut shift) = (0i64, 0);
    loop {
        let byte = b[*at];
        *at += 1;
        v |= ((byte & 0x7f) as i64) << shift;
        shift += 7;
        if byte & 0x80 == 0 {
            if shift < 64 && byte & 0x40 != 0 {
                v |= -1 << shift;
            }
            return v;
        }
    }
}

fn cstr(b: &[u8], at: &mut usize) -> String {
    let end = *at + b[*at..].iter().position(|&c| c == 0).unwrap();
    let s = String::from_utf8(b[*at..end].to_vec()).unwrap();
    *at = end + 1;
    s
}

/// The `.debug_line` of `obj` with its relocations applied for sections at address 0,
/// decoded (DWARF 3, 32-bit format, one unit).
fn decode(obj: &Object) -> Table {
    let s = obj
        .sections
        .iter()
        .find(|s| s.name == ".debug_line")
        .expect("a .debug_line section");
    assert_eq!((s.ty, s.flags, s.align), (1, 0, 1), "PROGBITS, no flags");
    let mut b = s.data.clone();
    for r in &s.relocs {
        assert_eq!(r.kind, R_SPU_ADDR32);
        let RelocTarget::Section(k) = r.target else {
            panic!("relocation against a symbol: {r:?}")
        };
        assert!(obj.sections[k].flags & 4 != 0, "against a code section");
        let at = r.offset as usize;
        assert_eq!(&b[at..at + 4], &[0; 4], "the field is left zero for RELA");
        b[at..at + 4].copy_from_slice(&(r.addend as u32).to_be_bytes());
    }
    let units = units(&b);
    assert_eq!(units.len(), 1, "one unit, the whole section");
    units.into_iter().next().unwrap()
}

/// Every unit of a `.debug_line` (relocated) in order.
fn units(all: &[u8]) -> Vec<Table> {
    let mut out = Vec::new();
    let mut start = 0;
    while start < all.len() {
        let len = u32::from_be_bytes(all[start..start + 4].try_into().unwrap()) as usize;
        out.push(unit(&all[start..start + 4 + len]));
        start += 4 + len;
    }
    out
}

/// One unit of a line table.
fn unit(b: &[u8]) -> Table {
    let be32 = |at: usize| u32::from_be_bytes(b[at..at + 4].try_into().unwrap());
    assert_eq!(u16::from_be_bytes([b[4], b[5]]), 3, "version");
    let header_length = be32(6) as usize;
    let program = 10 + header_length;
    let (min_insn, default_is_stmt, line_base, line_range, opcode_base) =
        (b[10], b[11] != 0, b[12] as i8, b[13], b[14]);
    assert_eq!(
        (
            min_insn,
            default_is_stmt,
            line_base,
            line_range,
            opcode_base
        ),
        (1, true, -5, 14, 13)
    );
    assert_eq!(&b[15..27], &[0, 1, 1, 1, 1, 0, 0, 0, 1, 0, 0, 1]);
    let mut at = 27;
    let mut dirs = Vec::new();
    while b[at] != 0 {
        dirs.push(cstr(b, &mut at));
    }
    at += 1;
    let mut files = Vec::new();
    while b[at] != 0 {
        let name = cstr(b, &mut at);
        let dir = uleb(b, &mut at);
        assert_eq!((uleb(b, &mut at), uleb(b, &mut at)), (0, 0), "time, size");
        files.push((name, dir));
    }
    at += 1;
    assert_eq!(at, program, "header_length");
    let mut rows = Vec::new();
    let fresh = || row(0, 1, 1, 0);
    let mut r = fresh();
    while at < b.len() {
        let op = b[at];
        at += 1;
        let emit = |r: &mut Row, rows: &mut Vec<Row>| {
            rows.push(r.clone());
            r.basic_block = false;
            r.prologue_end = false;
            r.epilogue_begin = false;
            r.discriminator = 0;
        };
        match op {
            0 => {
                let len = uleb(b, &mut at) as usize;
                let next = at + len;
                match b[at] {
                    1 => {
                        r.end_sequence = true;
                        rows.push(r.clone());
                        r = fresh();
                    }
                    2 => {
                        assert_eq!(len, 5);
                        r.address = be32(at + 1);
                    }
                    4 => {
                        let mut k = at + 1;
                        r.discriminator = uleb(b, &mut k) as u32;
                    }
                    e => panic!("extended opcode {e}"),
                }
                at = next;
            }
            1 => emit(&mut r, &mut rows),
            2 => r.address += uleb(b, &mut at) as u32,
            3 => r.line = (r.line as i64 + sleb(b, &mut at)) as u32,
            4 => r.file = uleb(b, &mut at) as u32,
            5 => r.column = uleb(b, &mut at) as u32,
            6 => r.is_stmt = !r.is_stmt,
            7 => r.basic_block = true,
            8 => r.address += ((255 - opcode_base) / line_range) as u32,
            9 => {
                r.address += u16::from_be_bytes([b[at], b[at + 1]]) as u32;
                at += 2;
            }
            10 => r.prologue_end = true,
            11 => r.epilogue_begin = true,
            12 => r.isa = uleb(b, &mut at) as u32,
            special => {
                let adjusted = (special - opcode_base) as i64;
                r.address += (adjusted / line_range as i64) as u32;
                r.line = (r.line as i64 + line_base as i64 + adjusted % line_range as i64) as u32;
                emit(&mut r, &mut rows);
            }
        }
    }
    assert_eq!(at, b.len());
    Table { dirs, files, rows }
}

fn hex(b: &[u8]) -> String {
    b.iter().map(|x| format!("{x:02x}")).collect()
}

#[test]
fn one_file_bytes_and_rows() {
    let obj = object(
        "\t.file 1 \"a.c\"\n\
         \t.text\n\
         \t.loc 1 3 0\n\
         \til $3,1\n\
         \til $3,2\n\
         \t.loc 1 5 2\n\
         \til $4,1\n\
         \t.loc 1 4 0 prologue_end\n\
         \tnop\n",
    );
    let s = obj
        .sections
        .iter()
        .find(|s| s.name == ".debug_line")
        .unwrap();
    // Hand-encoded: unit_length 0x34, version 3, header_length 0x1a, the state machine's
    // parameters and opcode lengths, no directories, "a.c" in directory 0; then
    // set_address 0, special (line +2), set_column 2, special (+8 bytes, line +2),
    // set_column 0, prologue_end, special (+4, line -1), advance_pc 4, end_sequence.
    assert_eq!(
        hex(&s.data),
        concat!(
            "00000034",
            "0003",
            "0000001a",
            "0101fb0e0d",
            "000101010100000001000001",
            "00",
            "612e6300000000",
            "00",
            "0005020000000014",
            "050284",
            "05000a49",
            "0204000101"
        )
    );
    assert_eq!(s.relocs.len(), 1);
    assert_eq!(
        (
            s.relocs[0].offset,
            s.relocs[0].kind,
            &s.relocs[0].target,
            s.relocs[0].addend
        ),
        (39, R_SPU_ADDR32, &RelocTarget::Section(0), 0)
    );
    let t = decode(&obj);
    assert!(t.dirs.is_empty());
    assert_eq!(t.files, vec![("a.c".to_string(), 0)]);
    let r1 = row(0, 1, 3, 0);
    let r2 = row(8, 1, 5, 2);
    let r3 = Row {
        prologue_end: true,
        ..row(12, 1, 4, 0)
    };
    let e = end(16, &r3);
    assert_eq!(t.rows, vec![r1, r2, r3, e]);
}

#[test]
fn sections_directories_options_and_long_advances() {
    let obj = object(
        "\t.file 1 \"src/a.c\"\n\
         \t.file 2 \"inc/b.h\"\n\
         \t.file 3 \"src/c.c\"\n\
         \t.section .text.two,\"ax\",@progbits\n\
         \t.loc 2 100 7 is_stmt 0\n\
         \til $3,1\n\
         \t.text\n\
         \t.loc 1 1 basic_block\n\
         \til $5,5\n\
         \t.space 400\n\
         \t.loc 1 30 discriminator 3 isa 2\n\
         \til $6,6\n\
         \t.loc 3 2 epilogue_begin\n\
         \t.loc 3 9\n\
         \til $7,7\n\
         \t.loc 3 10\n\
         \t.space 16\n\
         \til $8,8\n\
         \t.loc 3 11 view .LVU8\n\
         \t.loc 3 12 view .LVU9\n\
         \til $9,9\n\
         \t.long .LVU8, .LVU9\n",
    );
    let t = decode(&obj);
    assert_eq!(t.dirs, vec!["src".to_string(), "inc".to_string()]);
    assert_eq!(
        t.files,
        vec![
            ("a.c".to_string(), 1),
            ("b.h".to_string(), 2),
            ("c.c".to_string(), 1)
        ]
    );
    // .text.two got the first row, so its sequence is first.
    let two = Row {
        is_stmt: false,
        ..row(0, 2, 100, 7)
    };
    // Column and is_stmt carry over from `.loc` to `.loc` (dwarf2dbg.c's `current`);
    // isa too; basic_block, epilogue_begin and discriminator last one row.
    let at = |address, file, line| Row {
        is_stmt: false,
        isa: 2,
        ..row(address, file, line, 7)
    };
    let a = Row {
        basic_block: true,
        isa: 0,
        ..at(0, 1, 1)
    };
    let b = Row {
        discriminator: 3,
        ..at(404, 1, 30)
    };
    // Two `.loc`s in a row: the first gets a row where the second stands.
    let c = Row {
        epilogue_begin: true,
        ..at(408, 3, 2)
    };
    let d = at(408, 3, 9);
    // `.space` is no instruction: the row of `.loc 3 10` is at the next instruction.
    let e = at(428, 3, 10);
    // `view` makes the row at once; its symbol is the view number: 0 where the address
    // moved on from the section's row before, 1 for a second row at the same address.
    let f = at(432, 3, 11);
    let g = at(432, 3, 12);
    // The sequence ends where the section's contents end (after the `.long`).
    let last = end(444, &g);
    assert_eq!(
        t.rows,
        vec![two.clone(), end(4, &two), a, b, c, d, e, f, g, last]
    );
    let text = &obj.sections[0];
    assert_eq!(
        &text.data[436..444],
        &[0, 0, 0, 0, 0, 0, 0, 1],
        ".LVU8, .LVU9"
    );
    let dl = obj
        .sections
        .iter()
        .find(|s| s.name == ".debug_line")
        .unwrap();
    let targets: Vec<(&RelocTarget, i64)> =
        dl.relocs.iter().map(|r| (&r.target, r.addend)).collect();
    let two_index = obj
        .sections
        .iter()
        .position(|s| s.name == ".text.two")
        .unwrap();
    assert_eq!(
        targets,
        vec![
            (&RelocTarget::Section(two_index), 0),
            (&RelocTarget::Section(0), 0)
        ]
    );
}

#[test]
fn subsections_join_in_order_and_the_end_is_before_the_padding() {
    // Rows of subsection 1 follow those of subsection 0 whatever the source order; the
    // sequence ends where the contents end, before `.align` pads the section end.
    let obj = object(
        "\t.file 1 \"s.c\"\n\
         \t.text 1\n\
         \t.loc 1 20\n\
         \til $3,1\n\
         \t.text 0\n\
         \t.loc 1 10\n\
         \til $3,2\n\
         \til $3,3\n\
         \t.text 1\n\
         \t.align 4\n\
         \t.loc 1 21\n\
         \til $3,4\n",
    );
    let t = decode(&obj);
    let r = |a, l| row(a, 1, l, 0);
    assert_eq!(
        t.rows,
        vec![r(0, 10), r(8, 20), r(16, 21), end(20, &r(16, 21))]
    );
    assert_eq!(obj.sections[0].size, 32, "the section is padded to 16");
}

#[test]
fn advances_use_const_add_pc_and_advance_pc_as_gas() {
    // 20 bytes and +1 line: const_add_pc (17) then a special opcode for 3; 300 bytes:
    // advance_pc; a line -20: advance_line.
    let obj = object(
        "\t.file 1 \"x.c\"\n\
         \t.loc 1 1\n\
         \tnop\n\
         \t.space 16\n\
         \t.loc 1 2\n\
         \tnop\n\
         \t.space 296\n\
         \t.loc 1 40\n\
         \tnop\n\
         \t.loc 1 20\n\
         \tnop\n",
    );
    let s = obj
        .sections
        .iter()
        .find(|s| s.name == ".debug_line")
        .unwrap();
    let prog = &s.data[10 + 26..];
    // set_address 0 and DW_LNS_copy (line 1 is where a sequence starts); const_add_pc
    // and special 0x3d (+3 bytes, line +1); advance_line 38, advance_pc 300, copy;
    // advance_line -20 and special 0x4a (+4 bytes, line +0); advance_pc 4, end.
    assert_eq!(
        hex(prog),
        concat!(
            "0005020000000001",
            "083d",
            "0326",
            "02ac02",
            "01",
            "036c",
            "4a",
            "0204000101"
        )
    );
    let t = decode(&obj);
    let r = |a, l| row(a, 1, l, 0);
    assert_eq!(
        t.rows,
        vec![
            r(0, 1),
            r(20, 2),
            r(320, 40),
            r(324, 20),
            end(328, &r(324, 20))
        ]
    );
}

#[test]
fn no_loc_no_line_table_and_line_zero_makes_no_row() {
    let obj = object("\t.file 1 \"a.c\"\n\til $3,1\n");
    assert!(obj.sections.iter().all(|s| s.name != ".debug_line"));
    let obj = object("\t.file 1 \"a.c\"\n\t.loc 1 0\n\til $3,1\n");
    assert!(obj.sections.iter().all(|s| s.name != ".debug_line"));
    let obj = object("\t.file 1 \"a.c\"\n\t.loc 1 0\n\t.loc 1 7\n\til $3,1\n");
    assert_eq!(decode(&obj).rows[0], row(0, 1, 7, 0));
}

#[test]
fn labels_mark_basic_blocks_with_loc_mark_labels() {
    let obj = object(
        "\t.file 1 \"a.c\"\n\
         \t.loc_mark_labels 1\n\
         \t.loc 1 5\n\
         \til $3,1\n\
         here:\til $3,2\n",
    );
    let t = decode(&obj);
    let bb = Row {
        basic_block: true,
        ..row(4, 1, 5, 0)
    };
    assert_eq!(t.rows, vec![row(0, 1, 5, 0), bb.clone(), end(8, &bb)]);
}

fn diagnostics(src: &str) -> Vec<String> {
    let ds = match assemble_object(src, "t.s", &Options::default()) {
        Ok((_, w)) => w,
        Err(e) => e,
    };
    ds.iter()
        .map(|d| {
            format!(
                "{}:{}:{}: {}{}",
                d.location.file,
                d.location.line,
                d.location.column,
                if d.severity == Severity::Error {
                    "error: "
                } else {
                    "warning: "
                },
                d.message
            )
        })
        .collect()
}

#[test]
fn bad_operands_are_errors_at_file_line_column() {
    let cases: &[(&str, &str)] = &[
        ("\t.loc 2 1\n\tnop\n", "t.s:1:2: error: unassigned file number 2"),
        (
            "\t.file 1 \"a.c\"\n  .loc 1 x\n",
            "t.s:2:3: error: `x' is not a constant",
        ),
        (
            "\t.file 1 \"a.c\"\n\t.file 1 \"b.c\"\n",
            "t.s:2:2: error: file table slot 1 is already occupied by a different file (a.c vs b.c)",
        ),
        (
            "\t.file 1 \"a.c\"\n\t.loc 1 1 is_stmt 2\n",
            "t.s:2:2: error: is_stmt value not 0 or 1",
        ),
        (
            "\t.file 1 \"a.c\"\n\t.loc 1 1 frob\n",
            "t.s:2:2: error: unknown .loc sub-directive `frob'",
        ),
        ("\t.file 0 \"a.c\"\n", "t.s:1:2: error: file number 0 is DWARF 5's"),
        ("\t.file -1 \"a.c\"\n", "t.s:1:2: error: file number less than one"),
        ("\t.file 1 a.c\n", "t.s:1:2: error: expected a file name in double quotes"),
        (
            "\t.file 1 \"a.c\" junk\n",
            "t.s:1:2: error: junk at end of line, first unrecognized character is `j'",
        ),
        (
            "\t.file 1 \"a.c\"\n\t.loc 1 1 view 3\n",
            "t.s:2:2: error: numeric view can only be asserted to zero",
        ),
        (
            "\t.file 1 \"a.c\"\n\t.loc 1 1 isa -1\n",
            "t.s:2:2: error: isa number less than zero",
        ),
        (
            "\t.file 1 \"a.c\"\n\t.loc_mark_labels 2\n",
            "t.s:2:2: error: expected 0 or 1",
        ),
        (
            "\t.file 1 \"a.c\"\n\t.file 3 \"c.c\"\n\t.loc 1 1\n\tnop\n",
            "t.s:2:1: error: unassigned file number 2",
        ),
        (
            "\t.file 1 \"a.c\"\n\t.loc 1 1\n\tnop\n\t.section .debug_line\n\t.long 0\n",
            "t.s:1:1: error: duplicate .debug_line sections",
        ),
        (
            "\t.file 1 \"a.c\"\n\t.file 70000 \"c.c\"\n",
            "t.s:2:2: error: file number 70000 is too big",
        ),
    ];
    for (src, want) in cases {
        let got = diagnostics(src);
        assert!(
            got.iter().any(|g| g.starts_with(want)),
            "{src:?}: want {want:?}, got {got:?}"
        );
    }
}

#[test]
fn a_row_outside_code_is_dropped_with_gas_warning() {
    let src = "\t.file 1 \"a.c\"\n\t.data\n\t.loc 1 1\n\tnop\n";
    assert_eq!(
        diagnostics(src),
        vec!["t.s:4:2: warning: dwarf line number information for .data ignored"]
    );
    let (obj, _) = assemble_object(src, "t.s", &Options::default()).unwrap();
    assert!(obj.sections.iter().all(|s| s.name != ".debug_line"));
    // An executable has no .debug_line and assembles the same words.
    let plain = assemble("\tnop\n", "t.s", &Options::default()).unwrap();
    let with = assemble(
        "\t.file 1 \"a.c\"\n\t.loc 1 1\n\tnop\n",
        "t.s",
        &Options::default(),
    )
    .unwrap();
    assert_eq!(plain.image, with.image);
    assert!(with.warnings.is_empty());
}

#[test]
fn objects_with_debug_line_link_to_the_same_program() {
    let code = "\t.global _start\n_start:\tila $3,data\n\tbrsl $0,f\n\tstop\n";
    let other = "\t.global f\nf:\til $4,7\n\tbi $0\n\t.data\n\t.global data\ndata:\t.long 5\n";
    let with_lines = |src: &str| {
        let mut out = String::from("\t.file 1 \"m.c\"\n");
        for (i, l) in src.lines().enumerate() {
            if !l.contains(':') && !l.starts_with("\t.") {
                out += &format!("\t.loc 1 {}\n", i + 1);
            }
            out += l;
            out += "\n";
        }
        out
    };
    let plain = link(&[object(code), object(other)], &LinkOptions::default()).unwrap();
    let a = object(&with_lines(code));
    let b = object(&with_lines(other));
    assert!(a.sections.iter().any(|s| s.name == ".debug_line"));
    let linked = link(&[a, b], &LinkOptions::default()).unwrap();
    assert_eq!(linked.image, plain.image);
    assert_eq!(linked.entry, plain.entry);
    assert_eq!(linked.symbols, plain.symbols);
    // The executable keeps the debugging sections, joined and relocated as GNU ld does:
    // the second unit's rows are where `f` was placed, and its .debug_info's stmt_list is
    // the offset of its line table in the joined .debug_line.
    assert!(spu_asm::elf_check::layout_errors(&linked.elf).is_empty());
    use object::read::elf::ElfFile32;
    use object::{Object as _, ObjectSection as _};
    let elf = ElfFile32::<object::BigEndian>::parse(&linked.elf[..]).unwrap();
    let data = |name: &str| elf.section_by_name(name).unwrap().data().unwrap().to_vec();
    let f = linked.symbols.iter().find(|s| s.0 == "f").unwrap().1;
    let lines = units(&data(".debug_line"));
    assert_eq!(lines.len(), 2);
    // Line 3 of each source is its first line without a label: `brsl` at 4, `bi` at f+4.
    assert_eq!(lines[0].rows[0], row(4, 1, 3, 0));
    assert_eq!(lines[1].rows[0], row(f + 4, 1, 3, 0));
    let info = data(".debug_info");
    let first_unit = 4 + u32::from_be_bytes(info[0..4].try_into().unwrap()) as usize;
    let first_lines = 4 + u32::from_be_bytes(data(".debug_line")[0..4].try_into().unwrap());
    let stmt_list = &info[first_unit + 12..first_unit + 16];
    assert_eq!(stmt_list, first_lines.to_be_bytes());
    // The same program in the same segments: what loads is what ran before.
    let plain_elf = ElfFile32::<object::BigEndian>::parse(&plain.elf[..]).unwrap();
    use object::read::elf::ProgramHeader as _;
    let e = object::BigEndian;
    let segs = |x: &ElfFile32<object::BigEndian>| -> Vec<(u32, u32, u32)> {
        x.elf_program_headers()
            .iter()
            .map(|p| (p.p_vaddr(e), p.p_filesz(e), p.p_memsz(e)))
            .collect()
    };
    assert_eq!(segs(&elf), segs(&plain_elf));
}

fn section<'o>(obj: &'o Object, name: &str) -> &'o spu_asm::object::ObjSection {
    obj.sections
        .iter()
        .find(|s| s.name == name)
        .unwrap_or_else(|| panic!("no {name}"))
}

/// A section's relocations as (offset, target section or symbol name, addend).
fn relocs(obj: &Object, name: &str) -> Vec<(u32, String, i64)> {
    section(obj, name)
        .relocs
        .iter()
        .map(|r| {
            assert_eq!(r.kind, R_SPU_ADDR32);
            let t = match &r.target {
                RelocTarget::Section(k) => obj.sections[*k].name.clone(),
                RelocTarget::Symbol(n) => n.clone(),
            };
            (r.offset, t, r.addend)
        })
        .collect()
}

#[test]
fn gas_adds_a_compilation_unit_around_the_line_table() {
    // dwarf2_finish: with rows and no .debug_info of the source's own, gas writes a
    // DWARF 3 unit naming the first file, the working directory and itself, covering
    // the code of the one section with rows (low_pc; high_pc is where its contents end,
    // an explicit `.align` included: that is an alignment frag of the contents).
    let obj = object("\t.file 1 \"src/a.c\"\n\t.loc 1 3\n\til $3,1\n\tnop\n\t.align 4\n");
    let cwd = std::env::current_dir().unwrap();
    let pwd = std::env::var("PWD")
        .ok()
        .filter(|p| std::path::Path::new(p).canonicalize().ok() == cwd.canonicalize().ok())
        .unwrap_or_else(|| cwd.to_string_lossy().into_owned());
    let strs = format!("src/a.c\0{pwd}\0GNU AS 2.40\0");
    assert_eq!(section(&obj, ".debug_str").data, strs.as_bytes());
    assert_eq!(
        (
            section(&obj, ".debug_str").flags,
            section(&obj, ".debug_str").entsize
        ),
        (0x30, 1)
    );
    // compile_unit, no children: stmt_list data4, low_pc/high_pc addr, name, comp_dir and
    // producer strp, language data2.
    assert_eq!(
        hex(&section(&obj, ".debug_abbrev").data),
        "011100100611011201030e1b0e250e1305 0000 00".replace(' ', "")
    );
    assert_eq!(
        hex(&section(&obj, ".debug_info").data),
        concat!(
            "00000022", "0003", "00000000", "04", "01", "00000000", "00000000", "00000000",
            "00000000", "00000000", "00000000", "8001"
        )
    );
    let p = (9 + pwd.len()) as i64;
    assert_eq!(
        relocs(&obj, ".debug_info"),
        vec![
            (6, ".debug_abbrev".into(), 0),
            (12, ".debug_line".into(), 0),
            (16, ".text".into(), 0),
            (20, ".text".into(), 16),
            (24, ".debug_str".into(), 0),
            (28, ".debug_str".into(), 8),
            (32, ".debug_str".into(), p),
        ]
    );
    // aranges: version 2, the header padded to 16, (.text, 16), the terminator.
    let ar = section(&obj, ".debug_aranges");
    assert_eq!(ar.align, 8);
    assert_eq!(
        hex(&ar.data),
        concat!(
            "0000001c",
            "0002",
            "00000000",
            "04",
            "00",
            "00000000",
            "00000000",
            "00000010",
            "0000000000000000"
        )
    );
    assert_eq!(
        relocs(&obj, ".debug_aranges"),
        vec![(6, ".debug_info".into(), 0), (16, ".text".into(), 0)]
    );
    assert!(obj.sections.iter().all(|s| s.name != ".debug_ranges"));
}

#[test]
fn sized_functions_are_subprograms_and_two_sections_use_ranges() {
    let obj = object(
        "\t.file 1 \"a.c\"\n\
         \t.global f\n\
         \t.type f,@function\n\
         f:\t.loc 1 1\n\
         \til $3,1\n\
         \tbi $0\n\
         \t.size f,.-f\n\
         \t.section .text.b,\"ax\",@progbits\n\
         \t.type g,@function\n\
         g:\t.loc 1 9\n\
         \tbi $0\n\
         \t.size g,4\n",
    );
    // Abbreviations 2 (subprogram: name, external flag, type, low_pc, high_pc) and 3
    // (unspecified type); the unit has children and DW_AT_ranges.
    assert_eq!(
        hex(&section(&obj, ".debug_abbrev").data),
        concat!(
            "01110110065506030e1b0e250e1305 0000",
            "022e00030e3f0c491511011201 0000",
            "033b000000",
            "00"
        )
        .replace(' ', "")
    );
    let info = &section(&obj, ".debug_info").data;
    // After the unit's fixed part (4+2+4+1+1 + 4 stmt_list + 4 ranges + 12 strings + 2):
    // f (external) and g (local), each pointing at the unspecified type at 0x40.
    assert_eq!(
        hex(&info[34..]),
        concat!(
            "02", "00000000", "01", "40", "00000000", "00000000", "02", "00000000", "00", "40",
            "00000000", "00000000", "03", "00"
        )
    );
    assert_eq!(info.len(), 0x42);
    let r = relocs(&obj, ".debug_info");
    assert!(r.contains(&(16, ".debug_ranges".into(), 0)), "{r:?}");
    assert!(
        r.contains(&(41, "f".into(), 0)) && r.contains(&(45, "f".into(), 8)),
        "{r:?}"
    );
    assert!(
        r.contains(&(56, "g".into(), 0)) && r.contains(&(60, "g".into(), 4)),
        "{r:?}"
    );
    let ranges = section(&obj, ".debug_ranges");
    assert_eq!(
        hex(&ranges.data),
        concat!(
            "ffffffff00000000",
            "0000000000000000",
            "0000000000000000",
            "0000000000000000"
        )
    );
    assert_eq!(
        relocs(&obj, ".debug_ranges"),
        vec![
            (8, ".text".into(), 0),
            (12, ".text".into(), 8),
            (16, ".text.b".into(), 0),
            (20, ".text.b".into(), 4)
        ]
    );
    let strs = &section(&obj, ".debug_str").data;
    assert!(strs.ends_with(b"GNU AS 2.40\0f\0g\0"));
}

#[test]
fn dash_g_numbers_the_assembly_source_lines() {
    // GNU as -g: a row per source line that has an instruction (two on one line: one
    // row), file 1 the source as named with its directory, DWARF 2 in .debug_info (gas's
    // `dwarf_level` under -g), version 3 line table; checked against x86 GNU as 2.40 -g.
    let opts = Options {
        debug_lines: true,
        ..Default::default()
    };
    let src = "\t.text\nstart:\tnop\n\tnop ; nop\n\n\t.data\n\t.long 1\n\t.text\n\tnop\n\
               \t.section .text.b,\"ax\",@progbits\n\tnop\n\t.text\n\tnop\n";
    let (obj, _) = assemble_object(src, "sub/g.s", &opts).unwrap();
    let t = decode_all(&obj);
    assert_eq!(t[0].dirs, vec!["sub".to_string()]);
    assert_eq!(t[0].files, vec![("g.s".to_string(), 1)]);
    let r = |a, l| row(a, 1, l, 0);
    assert_eq!(
        t[0].rows,
        vec![
            r(0, 2),
            r(4, 3),
            r(12, 8),
            r(16, 12),
            end(20, &r(16, 12)),
            r(0, 10),
            end(4, &r(0, 10))
        ]
    );
    let s = section(&obj, ".debug_line");
    assert_eq!(
        hex(&s.data[10 + u32::from_be_bytes(s.data[6..10].try_into().unwrap()) as usize..]),
        "0005020000000013 4b 87 4e 0204000101 0005020000000003090102 04000101".replace(' ', "")
    );
    assert_eq!(&section(&obj, ".debug_info").data[4..6], &[0, 2]);
    // A `.file N` means the source brings its own line numbers: -g's rows go.
    let (obj, _) = assemble_object(
        "\tnop\n\t.file 1 \"a.c\"\n\t.loc 1 7\n\tnop\n",
        "g.s",
        &opts,
    )
    .unwrap();
    assert_eq!(
        decode(&obj).rows,
        vec![row(4, 1, 7, 0), end(8, &row(4, 1, 7, 0))]
    );
}

/// Every unit of an object's `.debug_line`, relocated for sections at address 0.
fn decode_all(obj: &Object) -> Vec<Table> {
    let s = section(obj, ".debug_line");
    let mut b = s.data.clone();
    for r in &s.relocs {
        let at = r.offset as usize;
        b[at..at + 4].copy_from_slice(&(r.addend as u32).to_be_bytes());
    }
    units(&b)
}
