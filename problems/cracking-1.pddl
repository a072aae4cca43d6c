; Twenty-three blocks, eight piles of two and seven alone; the goal: a tower of three
; (b9 on b7 on b3, b3 on the table), each of the three under another block at the start.
; Six actions if nothing cracks. Far more states than any memory: explored online.
(define (problem cracking-1)
  (:domain cracking-blocks)
  (:objects b0 b1 b2 b3 b4 b5 b6 b7 b8 b9 b10 b11 b12 b13 b14 b15 b16 b17 b18 b19 b20 b21 b22)
  (:init (handempty) (on b1 b2) (ontable b2) (clear b1) (on b3 b4) (ontable b4)
         (clear b3) (on b5 b6) (ontable b6) (clear b5) (on b7 b8) (ontable b8)
         (clear b7) (on b9 b10) (ontable b10) (clear b9) (on b11 b12) (ontable b12)
         (clear b11) (on b13 b14) (ontable b14) (clear b13) (on b17 b18) (ontable b18)
         (clear b17) (ontable b0) (clear b0) (ontable b15) (clear b15) (ontable b16)
         (clear b16) (ontable b19) (clear b19) (ontable b20) (clear b20) (ontable b21)
         (clear b21) (ontable b22) (clear b22))
  (:goal (and (on b9 b7) (on b7 b3) (ontable b3))))
