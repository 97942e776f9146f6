# Directives real SPU code uses, with the bytes GNU as gives them: sections with flags and
# types, the section stack, subsections, local commons, LEB128, .org and dot assignment,
# alignment with fill patterns, symbol attributes, pseudo-ops without their dot; each
# form checked against spu-elf-as 2.40.
# Layout (GNU ld's SPU order): .init at 0; .text at 0x20 (its alignment is 32), its
# subsections 0, 1, 2 joined in order (sub 0 is 0x4c bytes, so `late` is at 0x6c);
# .data.rel at 0x80; .bss at 0xa0 (buf, then flag at 0xac).
	.file	"gnu_directives.c"
	.file	1 "gnu_directives.c"
	.text
	.global	start
	.type	start, @function
start:	il $3,1			# => 40800083
	.section .init,"ax",@progbits
init:	il $4,2			# => 40800104
	.previous
	il $5,3			# => 40800185
	.pushsection .data.rel,"aw",@progbits
d1:	.long 0x11223344	# => 11223344
	.uleb128 624485		# => e58e26
	.sleb128 -123456	# => c0bb78
	.sleb128 63, 64, -64, -65	# => 3fc00040bf7f
	.uleb128 0		# => 00
	.popsection
	il $6,4			# => 40800206
	.text 1
late:	il $7,5
	.text 0
	ila $8,late		# => 42003608
	.size	start, .-start
	.loc 1 2 0
	.extern	elsewhere
	.weak	maybe
	.hidden	start
	.lcomm	buf, 12
	.lcomm	flag, 1
	ila $9,buf		# => 42005009
	ila $10,flag		# => 4200560a
	. = . + 4		# => 00000000
	.org 0x24		# => 0000000000000000
	.2byte 0x0102		# => 0102
	.balignw 8, 0x4020	# => 4020
	.balignl 16, 0xdeadbeef	# => deadbeef deadbeef
	.p2alignl 5, 0x00200000	# => 00200000 00200000 00200000 00200000
	il $11,6		# => 4080030b
	GLOBL	start
	EQU	answer, 42
	il $12,answer		# => 4080150c
	.subsection 2
	il $13,7
	.text
	il $14,8		# => 4080040e
