; A delivery robot carrying parcels between rooms, one at a time. Rooms are joined by
; open halls (walk) or by doors (pass). Knowledge only: no probabilities, no costs;
; gdq_pddl/data/dynamics/delivery.toml is reality (which doors jam, how often it slips).
(define (domain delivery)
  (:requirements :strips :typing)
  (:types room door parcel)
  (:predicates
    (at ?r - room)                    ; the robot is in ?r
    (hall ?from ?to - room)           ; ?from and ?to are joined by an open hall
    (door ?d - door ?from ?to - room) ; door ?d leads from ?from to ?to
    (in ?p - parcel ?r - room)        ; parcel ?p lies in room ?r
    (carrying ?p - parcel)
    (empty-handed))

  (:action walk
    :parameters (?from ?to - room)
    :precondition (and (at ?from) (hall ?from ?to))
    :effect (and (at ?to) (not (at ?from))))

  (:action pass
    :parameters (?from ?to - room ?d - door)
    :precondition (and (at ?from) (door ?d ?from ?to))
    :effect (and (at ?to) (not (at ?from))))

  (:action pick
    :parameters (?p - parcel ?r - room)
    :precondition (and (at ?r) (in ?p ?r) (empty-handed))
    :effect (and (carrying ?p) (not (in ?p ?r)) (not (empty-handed))))

  (:action drop
    :parameters (?p - parcel ?r - room)
    :precondition (and (at ?r) (carrying ?p))
    :effect (and (in ?p ?r) (empty-handed) (not (carrying ?p)))))
