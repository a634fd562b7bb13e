;; causalplan 0.1.0: the candle and a causal model of 'light'.
(define (domain causalplan-candle)
  (:requirements :strips :typing :negative-preconditions :conditional-effects :derived-predicates)
  (:types part fit)
  (:constants wax wick match - part)
  (:predicates
    (in-assembly ?p - part)
    (available ?f - fit)
    (moves ?f - fit ?p - part)
    (attaches-to ?f - fit ?p - part)
    (excludes ?f - fit ?g - fit)
    (ignite-fit ?f - fit)
    (insert-fit ?f - fit)
    ;; nodes of the causal graph
    (n-energy-is-released) ; energy is released
    (n-light) ; light
    (n-provide-energy) ; provide energy
    (n-start-the-process) ; start the process
    (n-turn-energy-into-light) ; turn energy into light
  )

  ;; Function nodes: true when a part carrying the function is in the assembly.
  (:derived (n-provide-energy) (in-assembly wax)) ; provide energy
  (:derived (n-start-the-process) (in-assembly match)) ; start the process
  (:derived (n-turn-energy-into-light) (in-assembly wick)) ; turn energy into light

  ;; Rules: one clause per rule; rules with the same effect are alternatives.
  ;; rule 1: provide energy AND start the process CAUSES energy is released
  (:derived (n-energy-is-released) (and (n-provide-energy) (n-start-the-process)))
  ;; rule 2: energy is released AND turn energy into light CAUSES light
  (:derived (n-light) (and (n-energy-is-released) (n-turn-energy-into-light)))

  ;; Assembly primitives: attach a new part to the assembly through a free fit.
  (:action ignite
    :parameters (?moving - part ?fixed - part ?fit - fit)
    :precondition (and (ignite-fit ?fit) (moves ?fit ?moving) (attaches-to ?fit ?fixed)
                       (available ?fit) (in-assembly ?fixed) (not (in-assembly ?moving)))
    :effect (and (in-assembly ?moving)
                 (forall (?other - fit) (when (excludes ?fit ?other) (not (available ?other))))))
  (:action insert
    :parameters (?moving - part ?fixed - part ?fit - fit)
    :precondition (and (insert-fit ?fit) (moves ?fit ?moving) (attaches-to ?fit ?fixed)
                       (available ?fit) (in-assembly ?fixed) (not (in-assembly ?moving)))
    :effect (and (in-assembly ?moving)
                 (forall (?other - fit) (when (excludes ?fit ?other) (not (available ?other))))))
)
