; The keys grid of domains/keys.pddl written in PPDDL: here the domain itself says how
; well its actions work, so it needs no dynamics file. With the overlay
; gdq_pddl/data/dynamics/keys-ppddl.toml (the step limit, and the mud cost as a
; distribution instead of its mean) its true model is exactly keys.pddl's with
; gdq_pddl/data/dynamics/keys.toml (tests/pddl/test_ppddl.py checks V* to 1e-9).
; keys.toml's per-door lock probabilities become two schemas: unlock for sound locks,
; unlock-stiff for the stiff ones (the red lock, c13).
(define (domain keys-ppddl)
  (:requirements :strips :typing :negative-preconditions :probabilistic-effects
                 :action-costs)
  (:types cell key)
  (:predicates
    (at ?c - cell)                 ; the robot is in ?c
    (adj ?from ?to - cell)         ; neighbouring cells
    (open ?c - cell)               ; ?c can be entered (floor, or an unlocked door)
    (locked ?c - cell)             ; ?c is a locked door
    (stiff ?c - cell)              ; the lock of ?c jams
    (fits ?k - key ?c - cell)      ; key ?k unlocks door ?c
    (key-at ?k - key ?c - cell)
    (has ?k - key)
    (stuck))                       ; a failed trial: the episode is over
  (:functions
    (total-cost) - number
    (move-cost ?from ?to - cell) - number)   ; 3.5 into or out of the mud (c22), else 1

  ; 1 time in 20 the wheels spin and nothing happens.
  (:action move
    :parameters (?from ?to - cell)
    :precondition (and (at ?from) (adj ?from ?to) (open ?to))
    :effect (and (increase (total-cost) (move-cost ?from ?to))
                 (probabilistic 0.95 (and (at ?to) (not (at ?from))))))

  (:action pickup
    :parameters (?k - key ?c - cell)
    :precondition (and (at ?c) (key-at ?k ?c))
    :effect (and (has ?k) (not (key-at ?k ?c)) (increase (total-cost) 1)))

  ; A sound lock opens 9 times in 10.
  (:action unlock
    :parameters (?from ?door - cell ?k - key)
    :precondition (and (at ?from) (adj ?from ?door) (locked ?door) (has ?k) (fits ?k ?door)
                       (not (stiff ?door)))
    :effect (and (increase (total-cost) 1)
                 (probabilistic 0.9 (and (open ?door) (not (locked ?door))))))

  ; A stiff lock opens half the time, and 3 times in 10 the key breaks in it.
  (:action unlock-stiff
    :parameters (?from ?door - cell ?k - key)
    :precondition (and (at ?from) (adj ?from ?door) (locked ?door) (has ?k) (fits ?k ?door)
                       (stiff ?door))
    :effect (and (increase (total-cost) 1)
                 (probabilistic 0.5 (and (open ?door) (not (locked ?door)))
                                0.3 (stuck)))))
