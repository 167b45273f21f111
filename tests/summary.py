#!/usr/bin/env python3
"""Print one closing line over meson test logs: 'N passed, N failed, N skipped'.
Counts individual test cases where a test program printed its own
'N passed, N failed' line, else the program as one case."""
import json
import re
import sys

passed = failed = skipped = 0
for path in sys.argv[1:]:
    with open(path) as f:
        for line in f:
            rec = json.loads(line)
            result = rec.get("result")
            m = re.search(r"^(\d+) passed, (\d+) failed", rec.get("stdout") or "", re.M)
            if result == "SKIP":
                skipped += 1
            elif m and result in ("OK", "FAIL"):
                passed += int(m.group(1))
                failed += int(m.group(2)) + (1 if result == "FAIL" and int(m.group(2)) == 0 else 0)
            elif result == "OK":
                passed += 1
            else:
                failed += 1
print(f"{passed} passed, {failed} failed, {skipped} skipped")
sys.exit(1 if failed else 0)
