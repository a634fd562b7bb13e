;; causalplan 0.1.0: the desk lamp and a causal model of 'light'.
(define (domain causalplan-desk_lamp)
  (:requirements :strips :typing :negative-preconditions :conditional-effects :derived-predicates)
  (:types part fit)
  (:constants base_with_cables light_bulb shade - part)
  (:predicates
    (in-assembly ?p - part)
    (available ?f - fit)
    (moves ?f - fit ?p - part)
    (attaches-to ?f - fit ?p - part)
    (excludes ?f - fit ?g - fit)
    (clip-fit ?f - fit)
    (screw-fit ?f - fit)
    ;; nodes of the causal graph
    (n-diffuse-light) ; diffuse light
    (n-light) ; light
    (n-provide-electricity) ; provide electricity
    (n-turn-electricity-into-light) ; turn electricity into light
  )

  ;; Function nodes: true when a part carrying the function is in the assembly.
  (:derived (n-diffuse-light) (in-assembly shade)) ; diffuse light
  (:derived (n-provide-electricity) (in-assembly base_with_cables)) ; provide electricity
  (:derived (n-turn-electricity-into-light) (in-assembly light_bulb)) ; turn electricity into light

  ;; Rules: one clause per rule; rules with the same effect are alternatives.
  ;; rule 1: provide electricity AND turn electricity into light AND diffuse light CAUSES light
  (:derived (n-light) (and (n-diffuse-light) (n-provide-electricity) (n-turn-electricity-into-light)))

  ;; Assembly primitives: attach a new part to the assembly through a free fit.
  (:action clip
    :parameters (?moving - part ?fixed - part ?fit - fit)
    :precondition (and (clip-fit ?fit) (moves ?fit ?moving) (attaches-to ?fit ?fixed)
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
