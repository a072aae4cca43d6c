; The robot's action knowledge for office navigation (Hayamizu et al., ICAPS 2021).
; Goal-independent and cheap: how positions connect, that a door must be open before
; the robot goes through it, and that it must stand at a door to ask for it to be
; opened. No probabilities, no costs: the planner ignores them, the learner learns them.
(define (domain office)
  (:requirements :strips :typing)
  (:types position door)
  (:predicates
    (at ?p - position)                      ; the robot stands at ?p
    (walkway ?from ?to - position)          ; adjacent, not across a door
    (floor ?p - position)                   ; ?p is open floor (no door there)
    (door-side ?p - position ?d - door)     ; ?p is one side of door ?d
    (connects ?d - door ?from ?to - position) ; ?d leads from ?from to ?to
    (open ?d - door)
    (closed ?d - door))

  ; Move to an adjacent open-floor position.
  (:action goto
    :parameters (?from ?to - position)
    :precondition (and (at ?from) (walkway ?from ?to) (floor ?to))
    :effect (and (at ?to) (not (at ?from))))

  ; Move to an adjacent position beside a door, facing it.
  (:action approach
    :parameters (?from ?to - position ?d - door)
    :precondition (and (at ?from) (walkway ?from ?to) (door-side ?to ?d))
    :effect (and (at ?to) (not (at ?from))))

  ; Standing at a closed door, ask a person to open it.
  (:action opendoor
    :parameters (?p - position ?d - door)
    :precondition (and (at ?p) (door-side ?p ?d) (closed ?d))
    :effect (and (open ?d) (not (closed ?d))))

  ; Cross an open door to its other side.
  (:action gothrough
    :parameters (?from ?to - position ?d - door)
    :precondition (and (at ?from) (connects ?d ?from ?to) (open ?d))
    :effect (and (at ?to) (not (at ?from)))))
