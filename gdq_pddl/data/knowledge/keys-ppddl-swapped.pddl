; Wrong knowledge of domains/keys-ppddl.pddl (case wrong-probabilities of `gdq-pddl
; knowledge`): the same types, predicates, actions, preconditions and outcomes, but other
; probabilities. The knowledge believes the two locks swapped: a sound lock (blue, c33)
; opens 3 times in 10 (reality: 9 in 10), the stiff red lock (c13) opens 9 times in 10
; and jams 1 time in 20 (reality: opens 5 in 10, jams 3 in 10). Every outcome keeps a
; chance above 0, so the reachable states are reality's (the learners' tables agree).
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

  ; (believed) A sound lock opens 3 times in 10.
  (:action unlock
    :parameters (?from ?door - cell ?k - key)
    :precondition (and (at ?from) (adj ?from ?door) (locked ?door) (has ?k) (fits ?k ?door)
                       (not (stiff ?door)))
    :effect (and (increase (total-cost) 1)
                 (probabilistic 0.3 (and (open ?door) (not (locked ?door))))))

  ; (believed) A stiff lock opens 9 times in 10, and 1 time in 20 the key breaks in it.
  (:action unlock-stiff
    :parameters (?from ?door - cell ?k - key)
    :precondition (and (at ?from) (adj ?from ?door) (locked ?door) (has ?k) (fits ?k ?door)
                       (stiff ?door))
    :effect (and (increase (total-cost) 1)
                 (probabilistic 0.9 (and (open ?door) (not (locked ?door)))
                                0.05 (stuck)))))
