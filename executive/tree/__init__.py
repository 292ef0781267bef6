"""The tree machinery: the catalogue of nodes, trees composed in a mission file, the tree a mission runs,
what it waits for, a tick's state, drawings, other tools' formats and the mission file's schema."""
