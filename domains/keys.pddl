; A robot in a grid with locked doors: a door cell can be entered once it is unlocked
; with the key that fits it, and keys must be picked up first. Knowledge only;
; gdq_pddl/data/dynamics/keys.toml is reality (which lock jams, which cells are mud).
(define (domain keys)
  (:requirements :strips :typing)
  (:types cell key)
  (:predicates
    (at ?c - cell)                 ; the robot is in ?c
    (adj ?from ?to - cell)         ; neighbouring cells
    (open ?c - cell)               ; ?c can be entered (floor, or an unlocked door)
    (locked ?c - cell)             ; ?c is a locked door
    (fits ?k - key ?c - cell)      ; key ?k unlocks door ?c
    (key-at ?k - key ?c - cell)
    (has ?k - key))

  (:action move
    :parameters (?from ?to - cell)
    :precondition (and (at ?from) (adj ?from ?to) (open ?to))
    :effect (and (at ?to) (not (at ?from))))

  (:action pickup
    :parameters (?k - key ?c - cell)
    :precondition (and (at ?c) (key-at ?k ?c))
    :effect (and (has ?k) (not (key-at ?k ?c))))

  (:action unlock
    :parameters (?from ?door - cell ?k - key)
    :precondition (and (at ?from) (adj ?from ?door) (locked ?door) (has ?k) (fits ?k ?door))
    :effect (and (open ?door) (not (locked ?door)))))
