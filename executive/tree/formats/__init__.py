"""A tree in other tools' formats: BehaviorTree.CPP's XML (Groot2), and a Python-built tree described as catalogue nodes."""
