"""Grade diagnoses of withheld-effect campaigns against their answers.

Usage: python3 scripts/grade_independent.py ANSWERS.json OUT_DIR
OUT_DIR/<campaign>/diagnosis.json per campaign. The rule (campaigns README): right when
`best` is the withheld effect, or the effect is in `indistinguishable` together with `best`
and that set rules out at least two of the five candidates; without an effect, right when
`best` is null. Exits 1 when fewer than 5 of 6 (or of all graded) are right.
"""
import json
import os
import sys


def right(diagnosis, effect):
    best = diagnosis["best"]
    if effect is None:
        return best is None
    together = diagnosis["indistinguishable"]
    return best == effect or (best is not None and effect in together and len(together) <= 3)


def main():
    answers = json.load(open(sys.argv[1]))
    out = sys.argv[2]
    graded = n_right = 0
    for name in sorted(answers):
        path = os.path.join(out, name, "diagnosis.json")
        if not os.path.exists(path):
            print(f"{name}: not diagnosed")
            continue
        d = json.load(open(path))
        effect = answers[name]["effect"]
        ok = right(d, effect)
        graded += 1
        n_right += ok
        ranking = ", ".join(f"{m['effect']} {m['gap']:.1f}" for m in d["ranking"])
        print(f"{name}: {'right' if ok else 'WRONG'} (withheld {effect}; best {d['best']}; "
              f"indistinguishable {d['indistinguishable']}; baseline gap {d['baseline']['gap']:.1f}; {ranking})")
    need = 5 if graded == 6 else graded - graded // 6
    print(f"{n_right} of {graded} right")
    sys.exit(0 if n_right >= need and graded > 0 else 1)


if __name__ == "__main__":
    main()
