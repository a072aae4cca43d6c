"""The sections of ``REPORT.md``, one module each with a ``write(w: Writer)``.

:mod:`.writer` holds what they share (options, the line buffer, number formats) and
:mod:`.verdicts` the verdict bookkeeping; :mod:`gdq_pddl.analysis.report` runs the
sections in order and assembles the file.
"""
