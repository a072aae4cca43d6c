"""The stubs of the graded exercises, as ``gdq-pddl exercises init DIR`` writes them: one
file per exercise, its function to fill in (each raises ``NotImplementedError`` here)."""
