; Three floors and three passengers going both ways.
(define (problem lift-2)
  (:domain lift)
  (:objects ground first second - floor ann bob cy - passenger)
  (:init (lift-at ground) (above first ground) (above second first)
         (waiting ann ground) (dest ann second)
         (waiting bob second) (dest bob ground)
         (waiting cy first) (dest cy second))
  (:goal (forall (?p - passenger) (served ?p))))
