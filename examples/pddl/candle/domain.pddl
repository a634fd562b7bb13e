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
    (n-burning) ; burning
    (n-draw-up-the-fuel) ; draw up the fuel
    (n-fuel-at-the-tip) ; fuel at the tip
    (n-light) ; light
    (n-provide-fuel) ; provide fuel
    (n-start-a-flame) ; start a flame
  )

  ;; Function nodes: true when a part carrying the function is in the assembly.
  (:derived (n-draw-up-the-fuel) (in-assembly wick)) ; draw up the fuel
  (:derived (n-provide-fuel) (in-assembly wax)) ; provide fuel
  (:derived (n-start-a-flame) (in-assembly match)) ; start a flame

  ;; Rules: one clause per rule; rules with the same effect are alternatives.
  ;; rule 1: provide fuel AND draw up the fuel CAUSES fuel at the tip
  (:derived (n-fuel-at-the-tip) (and (n-draw-up-the-fuel) (n-provide-fuel)))
  ;; rule 2: fuel at the tip AND start a flame CAUSES burning
  (:derived (n-burning) (and (n-fuel-at-the-tip) (n-start-a-flame)))
  ;; rule 3: burning CAUSES light
  (:derived (n-light) (n-burning))

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
