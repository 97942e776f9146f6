# Misuse of the directives of gnu_directives2.s, each reported where it is, none
# cascading into errors about other lines.
	.data
	.incbin "incbin.dat", 11	# error: 4:2: skip (11) or count (-1) invalid for file size (10)
	.incbin "incbin.dat", 2, 9	# error: 5:2: skip (2) or count (9) invalid for file size (10)
	.incbin "incbin.dat", -1	# error: 6:2: skip (-1) or count (11) invalid for file size (10)
	.incbin "no-such-file.bin"	# error: 7:2: file not found: no-such-file.bin
	.incbin				# error: 8:2: missing file name for .incbin
	.macro need a:req
	.byte \a
	.endm
	need				# error: 12:2: Missing value for required parameter `a' of macro `need'
	.purgem nosuch			# warning: 13:2: Attempt to purge non-existing macro `nosuch'
	.ifeqs ab, "ab"			# error: 14:9: .ifeqs needs two quoted strings
	.endif
	.ifzz 1				# error: 16:2: unknown pseudo-op: `.ifzz`
	.byte 1
	.else
	.byte 2
	.endif
	.struct 8
	.long 1				# error: 22:2: attempt to store non-zero value in section `*ABS*'
	.data
	.byte 3
	.text
	.nops 8				# error: 26:2: unimplemented .nops directive
