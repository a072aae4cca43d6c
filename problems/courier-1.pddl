; Two parcels from the depot: p1 to the market over the hill (or round by the mill),
; p2 to the mill. V* = 30.75 (tests/envs/test_own_domains.py derives it).
(define (problem courier-1)
  (:domain courier)
  (:objects depot mill market - site p1 p2 - parcel)
  (:init (at depot) (carrying p1) (carrying p2) (dest p1 market) (dest p2 mill)
         (road depot mill) (road mill depot) (road mill market) (road market mill)
         (hill depot market)
         (= (length depot mill) 1) (= (length mill depot) 1)
         (= (length mill market) 1) (= (length market mill) 1))
  (:goal (exists (?p - parcel) (delivered ?p)))
  (:goal-reward 20)
  (:metric maximize (reward)))
