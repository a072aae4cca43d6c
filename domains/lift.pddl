; A lift with conditional effects (gdq_pddl's own domain; docs/domains.md). Stopping at a
; floor lets out every passenger bound there and takes in every one waiting there (one
; forall of two when effects); a move to an adjacent floor works nine times in ten,
; otherwise the lift stays. The goal: every passenger served (a forall goal).
(define (domain lift)
  (:requirements :typing :conditional-effects :universal-preconditions
                 :disjunctive-preconditions :probabilistic-effects)
  (:types floor passenger)
  (:predicates (lift-at ?f - floor) (above ?upper ?lower - floor)
               (waiting ?p - passenger ?f - floor) (in ?p - passenger)
               (dest ?p - passenger ?f - floor) (served ?p - passenger))
  (:action move
    :parameters (?from ?to - floor)
    :precondition (and (lift-at ?from) (or (above ?from ?to) (above ?to ?from)))
    :effect (probabilistic 9/10 (and (lift-at ?to) (not (lift-at ?from)))))
  (:action stop
    :parameters (?f - floor)
    :precondition (lift-at ?f)
    :effect (forall (?p - passenger)
              (and (when (and (in ?p) (dest ?p ?f)) (and (served ?p) (not (in ?p))))
                   (when (waiting ?p ?f) (and (in ?p) (not (waiting ?p ?f))))))))
