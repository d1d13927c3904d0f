"""Mission fuzzing (`aeroexec fuzz`): generate the missions nobody flew, run them in the
deterministic simulator with properties on, and shrink what breaks to a mission a person
can read.

- `steps` (steps.py): a generated mission as data (commands, waits, world faults), and the
  mission script and world file it is written as;
- `strategies` (strategies.py): Hypothesis strategies drawn from a catalog (behaviors,
  argument values with their boundaries, the simulator's fault kinds);
- `oracle` (oracle.py): one mission run through `simulate()`, judged by the properties and
  the executive's own invariants;
- `search` (search.py): the Hypothesis search and shrink, in seeded chunks any replay
  executor runs, and the database of past failures re-run first;
- `mutate` (mutate.py): `-m MISSION`: a flown mission's commands, reordered, dropped,
  repeated and perturbed;
- `output` (output.py): the counterexamples written to DIR (mission, world, MCAP,
  the violated property) and their re-check;
- `crosscheck` (crosscheck.py): the verifier's findings against the fuzzer's.

A tool above replay and the verifier: it runs its chunks on replay's executors and
cross-checks the verifier's findings (docs/design.md#layers).
"""
