#!/usr/bin/env node
// A stand-in for bench/peers/manifold/robustness.mjs that misbehaves on purpose, for
// bench_robustness_worker_faults (robustness_worker_faults.cmake): it answers the first
// case with a refusal, kills itself with SIGSEGV on the second, hangs on the third and
// refuses every later one. The case count survives restarts in the file $FAULT_COUNT.
import { createInterface } from 'node:readline';
import { readFileSync, writeFileSync } from 'node:fs';

const countFile = process.env.FAULT_COUNT;
process.stdout.write(JSON.stringify({ ready: true }) + '\n');
for await (const line of createInterface({ input: process.stdin })) {
  if (line.trim() === '') continue;
  let seen = 0;
  try { seen = Number(readFileSync(countFile, 'utf8')); } catch { /* the first case */ }
  writeFileSync(countFile, String(seen + 1));
  if (seen === 1) process.kill(process.pid, 'SIGSEGV');
  if (seen === 2) await new Promise(() => setInterval(() => {}, 1000));
  process.stdout.write(JSON.stringify({ cuts: [], input_precision: 'float64',
                                        error: { kind: 'refused', detail: 'refused on purpose' } }) + '\n');
}
