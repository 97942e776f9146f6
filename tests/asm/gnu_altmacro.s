# .altmacro as GNU as reads it (macro.c in alternate mode): `<...>` arguments with `!`
# quoting, `%expr` arguments as their decimal value, LOCAL labels of their own per
# expansion, parameters named without a backslash; .noaltmacro turns it off; and the
# smaller directives gas has beside it (.def, .dc.*, .dcb.*, .ds.*, .octa, .fail).
	.altmacro
	.macro emit v, s
	LOCAL here
here:	.byte v
	.ascii "\s"
	.long here
	.endm
	.data
	emit %1+2, <ab>			# => 03616200000080
	emit <4>, <x!>y>		# => 04783e7900000087
	.noaltmacro
	.macro plain v
	.byte \v
	.endm
	plain 9				# => 09
	.def dd, 3
	.dc.b dd			# => 03
	.dc.w 0x1234			# => 1234
	.dc.l 5				# => 00000005
	.ds.b 2				# => 0000
	.dcb.w 2, 0x4142		# => 41424142
	.octa -2			# => ffffffffffffffff fffffffffffffffe
	.fail 600
# warning: 27:2: .fail 600 encountered
	.text
	il $3, 1			# => 40800083
