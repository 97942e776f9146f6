# Labels, .set/.equ/.eqv/=, .global, forward references, numeric local labels, `.`,
# sym@h / sym@l.
	.global start, later
	.globl other
	.set ten, 10
	.equ twenty, ten * 2
	.eqv thirty, twenty + ten
	val = 0x12345678
start:	il $3,ten		# => 40800503
	il $3,twenty		# => 40800a03
	il $3,thirty		# => 40800f03
	ilhu $4,val@h		# => 41091a04
	iohl $4,val@l		# => 60ab3c04
	ila $5,later		# => 42002605
	ilhu $6,later@h		# => 41000006
	iohl $6,later@l		# => 60802606
	br later		# => 32000580
	brsl $lr,start		# => 337ffb80
	brnz $3,1f		# => 21000083
1:	brz $3,2f		# => 20000083
2:	brhz $3,1b		# => 227fff83
	br 1b			# => 327fff00
	br .			# => 32000000
	br .+8			# => 32000100
here:	.word . - here		# => 00000000
	.word here		# => 00000040
other:	lnop			# => 00200000
later:	nop			# => 40200000
	.set ten, 11
	il $7,ten		# => 40800587
	ai $8,$9,(later-start)/4 # => 1c04c488
	.equ size, end - start
	il $10,size		# => 40802e0a
	# KNOWN GAP: using `size` before its .equ (GNU as resolves it) is "undefined symbol"
end:
	packed=ten+1		# `=` without spaces, as gas takes it
	il $8,packed		# => 40800608
	alias = later		# a label's other name
	br alias		# => 327ffd80
