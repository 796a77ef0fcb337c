#!/usr/bin/env python3
"""The folder-level include graph of the library (docs/architecture.md): a room is a folder (a header in
include/errfield/X/ and the sources in src/X/ are one room; compensation/ counts its stages as rooms).
Prints the rooms, the arrows (one per pair of rooms with an include) and those that run against the
floor order FLOORS, lowest first. Run from the repository root: /usr/bin/python3 scripts/include_graph.py"""
import re, pathlib, collections, sys
def room_of(path):
    p = str(path)
    p = re.sub(r'^(include/errfield/|src/)', '', p)
    parts = p.split('/')[:-1]
    if not parts or parts[0] == 'detail': return 'root'  # detail/ holds root headers' template bodies
    if parts[0] == 'compensation' and len(parts) > 1: return 'compensation/' + parts[1]
    return parts[0]
FLOORS = ['root', 'kernels', 'io', 'parallel', 'optim', 'report', 'variogram', 'kriging', 'idw', 'interpolation', 'sampling',
          'robot', 'readers', 'compensation/model', 'compensation/fitting', 'compensation/validation', 'compensation/planning',
          'compensation/tools', 'compensation', 'programs', 'reproduction', 'cli', 'python']
floor = {r: i for i, r in enumerate(FLOORS)}
header_room = {}
for h in list(pathlib.Path('include/errfield').rglob('*.hpp')) + list(pathlib.Path('src').rglob('*.hpp')) + list(pathlib.Path('kernels').rglob('*.hpp')):
    s = str(h)
    key = re.sub(r'^include/', '', s) if s.startswith('include/') else re.sub(r'^src/', '', s)
    header_room[key] = 'kernels' if s.startswith('kernels/') else room_of(h)
    if s.startswith('kernels/'): header_room[s[len('kernels/'):]] = 'kernels'
arrows = collections.Counter()
for f in list(pathlib.Path('src').rglob('*.[ch]pp')) + list(pathlib.Path('include/errfield').rglob('*.hpp')) + list(pathlib.Path('kernels').rglob('*.[ch]pp')):
    src_room = 'kernels' if str(f).startswith('kernels/') else room_of(f)
    for inc in re.findall(r'#include "([^"]+)"', f.read_text(errors='replace')):
        dst = header_room.get(inc)
        if dst and dst != src_room: arrows[(src_room, dst)] += 1
up = [(a, b, n) for (a, b), n in arrows.items() if floor.get(b, 99) > floor.get(a, 99)]
print(f"{len(set(a for a,_ in arrows) | set(b for _,b in arrows))} rooms, {len(arrows)} arrows, {len(up)} running back up")
for a, b, n in sorted(up): print(f"  up: {a} -> {b} ({n} includes)")
unknown = set(a for a,_ in arrows if a not in floor) | set(b for _,b in arrows if b not in floor)
if unknown: print("rooms without a floor:", sorted(unknown))
