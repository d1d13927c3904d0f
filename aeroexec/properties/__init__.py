"""Properties in signal temporal logic: what must hold in every flight (docs/properties.md).

- `spec` (spec.py): property files and the built-in set `aeroexec:safety`;
- `signals` (signals.py): the signals of a session, sampled on the executive's tick, from
  a recording or from the bus;
- `lexer`, `parser`, `nodes`: formulas in RTAMT's STL syntax, tokenized (only the tokens
  of an expression), parsed into a tree of frozen dataclasses;
- `formula` (formula.py) and `semantics` (semantics.py): a formula checked and parsed,
  evaluated with RTAMT's semantics on numpy arrays (verdicts by the Boolean semantics,
  robustness by the quantitative one);
- `check` (check.py): evaluation of a property set over signals or a recording, the oracle
  `aeroexec check`, `replay --spec` and the what-if tools call;
- `monitor` (monitor.py): the same, online, as a bus observer (`run --spec`, `fly --spec`);
- `report` (report.py): `aeroexec check`'s text, json, sarif, junit and github outputs.

A tool beside replay and the verifier: it uses the layers below (recording, executive,
catalog) and none of them uses it. The submodules are imported where needed.
"""
