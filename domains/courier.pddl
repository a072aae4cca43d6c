; A courier with parcels, in PPDDL with rewards (gdq_pddl's own domain; docs/domains.md).
; Driving a road costs its length; the shortcut over the hill costs 3 and breaks the van
; down one time in four (a failed trial). Delivering a parcel earns 5, and 20 more if it
; is on time: any ordinary drive makes the courier late. The goal is one parcel
; delivered (an (exists ...) goal), which the problem rewards once with (:goal-reward).
(define (domain courier)
  (:requirements :typing :rewards :probabilistic-effects :conditional-effects
                 :existential-preconditions :negative-preconditions)
  (:types site parcel)
  (:predicates (at ?s - site) (road ?from ?to - site) (hill ?from ?to - site)
               (carrying ?p - parcel) (dest ?p - parcel ?s - site)
               (delivered ?p - parcel) (late) (stuck))
  (:functions (length ?from ?to - site))
  (:action drive
    :parameters (?from ?to - site)
    :precondition (and (at ?from) (road ?from ?to))
    :effect (and (at ?to) (not (at ?from)) (late)
                 (decrease (reward) (length ?from ?to))))
  (:action shortcut
    :parameters (?from ?to - site)
    :precondition (and (at ?from) (hill ?from ?to))
    :effect (and (decrease (reward) 3)
                 (probabilistic 3/4 (and (at ?to) (not (at ?from)))
                                1/4 (stuck))))
  (:action deliver
    :parameters (?p - parcel ?s - site)
    :precondition (and (at ?s) (carrying ?p) (dest ?p ?s))
    :effect (and (delivered ?p) (not (carrying ?p)) (increase (reward) 5)
                 (when (not (late)) (increase (reward) 20)))))
