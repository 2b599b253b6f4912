; realtime: 1012ms:! 1309ms:~ 1091ms:! 1428ms:~ 404ms:0x95
; random program, seed 268613718 (.ci/emu-random)
; the image traced a G2 the wrong way round when the preparation task was entered with SP at 4 mod 8 (CCR.STKALIGN was left clear: emu/tests/stack.rs); fixed by setting it in init
$122=59.6
$11=0.007
$121=202.0
G21 G90 G17 G94
G1 F1500
G1 X0.0625 Y0.0625
F150.0000
G1 X0.1025 Y0.0000
G2 X2.4483 Y3.4065 R-4.3823
G0 X4.1515 Y1.6518
M5
G3 X0.6437 Y3.3945 I-1.6331 J1.1145
G4 P0.01
$120=447.1
G1 X6.2212 Y-0.7956
M5
