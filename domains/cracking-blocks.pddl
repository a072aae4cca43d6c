; Blocks that crack (gdq_pddl's own domain; docs/domains.md, "Problems too large to
; enumerate"). A block set down on the table cracks one time in ten, and the table
; breaks one time in twenty (then nothing can be put down on it); a block stacked on
; another cracks the one below one time in five. A cracked block can be neither picked
; up nor built on. With many blocks the states are far too many to list: gdq-pddl
; explores such a problem online.
(define (domain cracking-blocks)
  (:requirements :strips :negative-preconditions :probabilistic-effects)
  (:predicates (on ?x ?y) (ontable ?x) (clear ?x) (handempty) (holding ?x)
               (cracked ?x) (table-broken))
  (:action pick-up :parameters (?x)
    :precondition (and (clear ?x) (ontable ?x) (handempty) (not (cracked ?x)))
    :effect (and (holding ?x) (not (clear ?x)) (not (ontable ?x)) (not (handempty))))
  (:action put-down :parameters (?x)
    :precondition (and (holding ?x) (not (table-broken)))
    :effect (and (ontable ?x) (clear ?x) (handempty) (not (holding ?x))
                 (probabilistic 0.05 (table-broken) 0.1 (cracked ?x))))
  (:action unstack :parameters (?x ?y)
    :precondition (and (on ?x ?y) (clear ?x) (handempty) (not (cracked ?x)))
    :effect (and (holding ?x) (clear ?y) (not (clear ?x)) (not (on ?x ?y))
                 (not (handempty))))
  (:action stack :parameters (?x ?y)
    :precondition (and (holding ?x) (clear ?y) (not (cracked ?y)))
    :effect (and (on ?x ?y) (clear ?x) (handempty) (not (holding ?x)) (not (clear ?y))
                 (probabilistic 0.2 (cracked ?y)))))
