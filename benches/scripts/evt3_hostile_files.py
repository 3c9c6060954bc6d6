#!/usr/bin/env python3
"""Writes broken and edge-case EVT3 files for the decoder identity check
(`benches/scripts/compare_evt3_outputs.sh`): events before the first TIME_HIGH, x or y
outside the header's sensor (early and deep in the file), time going backwards (with and
without events between), a file cut mid-word, vectors at the right edge, TIME_HIGH
wrap-around, no geometry, random word streams. usage: evt3_hostile_files.py OUT_DIR"""
import random, struct, os
import sys
D = sys.argv[1]
os.makedirs(D, exist_ok=True)
def header(w=240, h=180):
    if w is None:
        return b"% evt 3.0\n% format EVT3\n% end\n"
    return f"% evt 3.0\n% format EVT3;height={h};width={w}\n% geometry {w}x{h}\n% end\n".encode()
Y=lambda v:(0x0<<12)|v
X=lambda v,on=1:(0x2<<12)|(on<<11)|v
VB=lambda v,on=1:(0x3<<12)|(on<<11)|v
V12=lambda b:(0x4<<12)|b
V8=lambda b:(0x5<<12)|b
TL=lambda v:(0x6<<12)|v
TH=lambda v:(0x8<<12)|v
def write(name, words, w=240, h=180, tail=b""):
    with open(os.path.join(D, name), 'wb') as f:
        f.write(header(w, h)); f.write(struct.pack(f'<{len(words)}H', *words)); f.write(tail)
def valid_run(n, rng, t0=0, w=240, h=180, vect=False):
    out=[]; t=t0; high=None
    for i in range(n):
        t += rng.choice([0,0,1,1,2,5])
        hi, lo = (t>>12)&0xfff, t&0xfff
        if hi != high or rng.random()<0.1: out.append(TH(hi)); high=hi
        out.append(TL(lo))
        out.append(Y(rng.randrange(h)))
        if vect and rng.random()<0.3:
            base=rng.randrange(w-20); out.append(VB(base, rng.randrange(2))); out.append(V12(rng.randrange(4096)))
            if rng.random()<0.5: out.append(V8(rng.randrange(256)))
        else:
            out.append(X(rng.randrange(w), rng.randrange(2)))
        if rng.random()<0.05: out.append(rng.choice([0x7000,0xe123,0xf456,0xa000]))
    return out
r=random.Random(1)
# 1 events before the first TIME_HIGH (one outside the sensor), skipped
write('01_before_time_high.raw', [Y(5),X(10),X(400),TL(3),Y(300),X(5)] + valid_run(2000, r, 100))
# 2 x outside, early and deep (after several fast blocks)
write('02_x_outside_early.raw', [TH(0),TL(1),Y(10),X(20),X(300)] + valid_run(100, r))
write('03_x_outside_deep.raw', valid_run(300000, r) + [Y(10),X(240)] + valid_run(100, r, 10**6))
# 4 y outside (with an event), and y outside without an event (no error)
write('04_y_outside_deep.raw', valid_run(200000, r) + [Y(180),X(3)] + valid_run(100, r, 10**6))
write('05_y_outside_no_event.raw', valid_run(200000, r) + [Y(180),Y(2000),TL(5),Y(3),X(3)] + valid_run(100, r, 10**6))
# 6 time backwards: with events between, and without
bw = valid_run(150000, r) + [TL(5), Y(1), X(1)] + valid_run(150000, r, 700000) + [TH(0), TL(0), Y(2), X(2)] + valid_run(1000, r, 900000)
write('06_time_backwards.raw', bw)
write('07_time_backwards_no_event.raw', valid_run(150000, r) + [TL(5), TL(4000)] + valid_run(1000, r, 10**6))
# 8 cut mid-word
write('08_cut_mid_word.raw', valid_run(100000, r), tail=b"\x01")
# 9 vector at the right edge: valid (228..239), then outside (236..247)
write('09_vector_right_edge_ok.raw', valid_run(50000, r) + [Y(7), VB(228), V12(0xfff), V8(0), VB(232,0), V8(0x80)] + valid_run(100, r, 10**6))
write('10_vector_right_edge_out.raw', valid_run(50000, r) + [Y(7), VB(228), V12(0xfff), V8(0x01)] + valid_run(100, r, 10**6))
# 11 time-high wrap-around (loops) and a small step back (no loop: backwards)
wrap = [TH(4000), TL(1), Y(1), X(1), TH(4095), TL(7), Y(1), X(2), TH(3), TL(2), Y(2), X(3)] + valid_run(50000, r, 0) + [TH(4090), TL(9), Y(3), X(3), TH(1), TL(0), Y(4), X(4)] + [TH(3000), TL(1), Y(5), X(5), TH(2000), TL(1), Y(6), X(6)]
write('11_time_high_wrap.raw', wrap)
# 12 vectors and polarity carried from ADDR_X to a vector without a base; valid, big
vr = valid_run(400000, r, vect=True)
vr += [Y(3), X(5, 0), V12(0x3), X(7, 1), V8(0x1), TL(0xfff)]
vr += valid_run(1000, r, 10**7, vect=True)
write('12_vectors_valid.raw', vr)
# 13 no geometry (sensor inferred up to 4096): vectors beyond x 2047, and x wrapping
nog = valid_run(20000, r, w=240) + [Y(9), VB(2047), V12(0xfff), V12(0x801)] + [V12(0x1)]*5600 + [Y(10), V8(0xff)] + valid_run(1000, r, 10**6)
write('13_no_geometry_wide_vectors.raw', nog, w=None)
# 14/15 random words (fuzz): mostly valid types, unsorted times; big sensor so bounds rarely fail
def fuzz(n, rng):
    ws=[TH(0)]
    for i in range(n):
        k = rng.choices([0,2,3,4,5,6,8,7,14,15], [20,25,3,4,3,20,5,2,2,2])[0]
        ws.append((k<<12) | rng.randrange(4096))
    return ws
write('14_fuzz_2048.raw', fuzz(600000, random.Random(14)), w=2048, h=2048)
write('15_fuzz_none.raw', fuzz(600000, random.Random(15)), w=None)
write('16_fuzz_640.raw', fuzz(600000, random.Random(16)), w=640, h=480)
# 17 empty data, 18 only time words
write('17_empty.raw', [])
write('18_only_time.raw', [TH(1), TL(2), TH(2), TL(5)])
# 19 the header's sensor small: ADDR_X exactly width-1 and width
write('19_x_at_width.raw', [TH(0), TL(0), Y(179), X(239), Y(0), X(240)])
