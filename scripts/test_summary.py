#!/usr/bin/env python3
"""Counts the test cases in catkin's JUnit XML results and prints one closing
line 'tests: N passed, N failed, N skipped'. Exits 1 when a test failed or
errored, or when no test ran at all (a missing result file counts as an error)."""
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

root = Path(sys.argv[1] if len(sys.argv) > 1 else ".")
passed = failed = skipped = 0
broken = []
for xml in sorted(root.rglob("*.xml")):
    try:
        tree = ET.parse(xml)
    except ET.ParseError as e:
        broken.append(f"{xml.name}: unreadable result file ({e})")
        continue
    for case in tree.iter("testcase"):
        name = f"{case.get('classname', '')}.{case.get('name', '')}"
        if case.find("failure") is not None or case.find("error") is not None:
            failed += 1
            broken.append(f"FAILED {xml.name}: {name}")
        elif case.find("skipped") is not None or case.get("status") == "notrun":
            skipped += 1
        else:
            passed += 1
for line in broken:
    print(line)
print(f"tests: {passed} passed, {failed + len([b for b in broken if not b.startswith('FAILED')])} failed, {skipped} skipped")
sys.exit(1 if broken or failed or passed == 0 else 0)
