# The directives GNU as 2.40 has that an earlier version of this assembler refused
# (issue #31): .incbin, .ifb/.ifnb, .ifeqs/.ifnes, .ifge and friends, .purgem, :req and
# :vararg parameters, .struct; each with the bytes spu-elf-as gives it.
	.struct 0
f_a:	.space 4
f_b:	.long 0
f_c:	.skip 8
f_size:
	.data
	.long f_a, f_b, f_c, f_size	# => 00000000 00000004 00000008 00000010
	.incbin "incbin.dat"		# => 41424344 45464748 494a
	.incbin "incbin.dat", 2		# => 43444546 4748494a
	.incbin "incbin.dat", 3, 2	# => 4445
	.macro sum first, rest:vararg
	.byte \first
	.ifnb \rest
	sum \rest
	.endif
	.endm
	sum 1, 2, 3			# => 010203
	.macro need a:req, b=5
	.byte \a, \b
	.endm
	need 7				# => 0705
	need b=9, a=8			# => 0809
	.purgem need
	.macro need
	.byte 0x66
	.endm
	need				# => 66
	.ifeqs "ab", "a\x62"
	.byte 0x11			# => 11
	.endif
	.ifnes "ab", "ab"
	.byte 0x22
	.else
	.byte 0x23			# => 23
	.endif
	.ifb
	.byte 0x24			# => 24
	.endif
	.ifge -1
	.byte 0x33
	.elseif 2 > 1
	.byte 0x34			# => 34
	.endif
	.iflt -1
	.byte 0x35			# => 35
	.endif
	.ifle 0
	.byte 0x36			# => 36
	.endif
	.ifgt 0
	.byte 0x37
	.endif
	.ifnotdef nothing
	.byte 0x38			# => 38
	.endif
	.irep r, 5, 6
	.byte \r			# => 05060a0a0708
	.endr
	.rep 2
	.byte 0x0a
	.endr
	.irepc c, 78
	.byte \c
	.endr
	.text
	il $3, f_size			# => 40800803
