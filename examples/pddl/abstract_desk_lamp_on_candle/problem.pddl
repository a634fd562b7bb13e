(define (problem candle-n-light)
  (:domain causalplan-candle)
  (:objects wick_into_wax match_lights_wick - fit)
  (:init
    (in-assembly wax)
    ;; wick_into_wax: Insert the wick into the wax.
    (available wick_into_wax) (insert-fit wick_into_wax) (moves wick_into_wax wick) (attaches-to wick_into_wax wax) (excludes wick_into_wax wick_into_wax)
    ;; match_lights_wick: Light the wick with the match.
    (available match_lights_wick) (ignite-fit match_lights_wick) (moves match_lights_wick match) (attaches-to match_lights_wick wick) (excludes match_lights_wick match_lights_wick)
  )
  (:goal (n-light)) ; light
)
