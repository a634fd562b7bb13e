;; causalplan 0.1.0: the flashlight and a causal model of 'light'.
(define (domain causalplan-flashlight)
  (:requirements :strips :typing :negative-preconditions :conditional-effects :derived-predicates)
  (:types part fit)
  (:constants case head batteries - part)
  (:predicates
    (in-assembly ?p - part)
    (available ?f - fit)
    (moves ?f - fit ?p - part)
    (attaches-to ?f - fit ?p - part)
    (excludes ?f - fit ?g - fit)
    (insert-fit ?f - fit)
    (screw-fit ?f - fit)
    ;; nodes of the causal graph
    (n-close-the-circuit) ; close the circuit
    (n-electricity-flows) ; electricity flows
    (n-light) ; light
    (n-provide-electricity) ; provide electricity
    (n-turn-electricity-into-light) ; turn electricity into light
  )

  ;; Function nodes: true when a part carrying the function is in the assembly.
  (:derived (n-close-the-circuit) (in-assembly head)) ; close the circuit
  (:derived (n-provide-electricity) (in-assembly batteries)) ; provide electricity
  (:derived (n-turn-electricity-into-light) (in-assembly head)) ; turn electricity into light

  ;; Rules: one clause per rule; rules with the same effect are alternatives.
  ;; rule 1: provide electricity AND close the circuit CAUSES electricity flows
  (:derived (n-electricity-flows) (and (n-close-the-circuit) (n-provide-electricity)))
  ;; rule 2: electricity flows AND turn electricity into light CAUSES light
  (:derived (n-light) (and (n-electricity-flows) (n-turn-electricity-into-light)))

  ;; Assembly primitives: attach a new part to the assembly through a free fit.
  (:action insert
    :parameters (?moving - part ?fixed - part ?fit - fit)
    :precondition (and (insert-fit ?fit) (moves ?fit ?moving) (attaches-to ?fit ?fixed)
                       (available ?fit) (in-assembly ?fixed) (not (in-assembly ?moving)))
    :effect (and (in-assembly ?moving)
                 (forall (?other - fit) (when (excludes ?fit ?other) (not (available ?other))))))
  (:action screw
    :parameters (?moving - part ?fixed - part ?fit - fit)
    :precondition (and (screw-fit ?fit) (moves ?fit ?moving) (attaches-to ?fit ?fixed)
                       (available ?fit) (in-assembly ?fixed) (not (in-assembly ?moving)))
    :effect (and (in-assembly ?moving)
                 (forall (?other - fit) (when (excludes ?fit ?other) (not (available ?other))))))
)
