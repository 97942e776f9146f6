# Sections and alignment: .text .data .bss .section .align .balign .p2align,
# nop/lnop padding in text (lnop in an odd slot, then nop/lnop pairs), fill in data.
	.text
start:	il $3,1			# => 40800083
	.align 4		# => 00200000 40200000 00200000
	il $4,2			# => 40800104
	.balign 8		# => 00200000
	il $5,3			# => 40800185
	.p2align 3		# => 00200000
	il $6,4			# => 40800206
	.p2align 4,,8		/* needs 12 bytes, more than 8, so skipped */
	il $7,5			# => 40800287
	.p2align 4,,8		# => 40200000 00200000
	.balign 16		/* already aligned, so no bytes */
	# Executable layout as GNU ld's SPU script: code, then .rodata, then the data
	# segment from ALIGN(0x80), .data and .bss, each at its alignment (at least 16):
	# .rodata at 0x40, .data at 0x80, .bss at 0xa0.
	ila $6,dval		# => 42004006
	ila $7,bval		# => 42005007
	ila $8,rval		# => 42002008
	.data
dval:	.byte 1			# => 01
	.align 2		# => 000000
	.long 0x11223344	# => 11223344
	.byte 2			# => 02
	.balign 8,0xee		# => eeeeeeeeeeeeee
	.quad 5			# => 0000000000000005
	.section .rodata
rval:	.byte 0xa5		# => a5
	.p2align 2,0x5a		# => 5a5a5a
	.section .bss
bval:	.space 16
	.section .text
	il $9,4			# => 40800209
