; realtime: 466ms:! 821ms:~ 1361ms:! 1572ms:~ 251ms:0x90
; random program, seed 1265515129 (.ci/emu-random), with $210=1 (S-curve) mid-job: 3.95 % longer on the image before the cosine ramp's Newton solve converged within f32 (issue 23)
$111=1071
G21 G90 G17 G94
G1 F1500
G1 X-1.2077 Y7.6439
G4 P0.01
$210=1
G0 X-7.2378 Y1.5938
G2 X-9.8674 Y-3.3572 R-3.5438
G1 X-2.5852 Y-8.3379
M5
G1 X-8.4888 Y-10.3753
M5
