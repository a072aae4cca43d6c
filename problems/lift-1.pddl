; One passenger from the ground floor up: stop, move (9/10), stop.
; V* = 161/9 (tests/envs/test_own_domains.py derives it).
(define (problem lift-1)
  (:domain lift)
  (:objects ground first - floor ann - passenger)
  (:init (lift-at ground) (above first ground) (waiting ann ground) (dest ann first))
  (:goal (forall (?p - passenger) (served ?p))))
