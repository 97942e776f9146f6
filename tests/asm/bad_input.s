# Input GNU as takes silently or wrongly, rejected here with a message; and directive
# misuse with the message gas gives.
	ai	$-1, $3, 1		# error: 3:5: register number -1 out of range [0, 127]
	ai	$3, (200), 1		# error: 4:9: register number 200 out of range [0, 127]
	lqd	$3, 0($130)		# error: 5:12: register number 130 out of range [0, 127]
	wrch	$ch200, $3		# error: 6:7: channel number 200 out of range
	rotqbyi	$3, $4, 200		# GNU as keeps the low 7 bits of a rotate count (as here)
	.popsection			# warning: 8:2: .popsection without corresponding .pushsection
	.byte	1
	.balignl 4, 0x01020304		# error: 10:2: alignment padding (3 bytes) not a multiple of 4
	.org	0			# error: 11:2: attempt to move .org backwards
	.rept	2000000			# error: 12:1: .rept count 2000000 is more than 1048576
	nop
	.endr
	.section .x,"q"			# error: 15:2: unknown section attribute `q'
	.section .y,"a",@weird		# error: 16:2: unrecognized section type `weird'
	.type	f, @gizmo		# error: 17:2: unrecognized symbol type
	.reloc	0, R_SPU_ADDR32		# error: 18:2: unrecognized reloc type `R_SPU_ADDR32'
	.lcomm	big, 0x100000		# error: 19:2: .lcomm length (1048576) out of range
	.lcomm	odd, 4, 3		# error: 20:2: junk at end of line
	.cfi_startproc			# error: 21:2: CFI is not supported for this target
	set	x, 1			# error: 22:2: Invalid mnemonic 'set'
	.comm	c, 4, 3			# error: 23:2: alignment 3 is not a power of 2
