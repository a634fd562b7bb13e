(define (problem kerosene_lamp-n-light)
  (:domain causalplan-kerosene_lamp)
  (:objects burner_onto_tank wick_into_burner lighter_lights_wick chimney_onto_burner - fit)
  (:init
    (in-assembly fuel_tank)
    ;; burner_onto_tank: Screw the burner onto the fuel tank with kerosene.
    (available burner_onto_tank) (screw-fit burner_onto_tank) (moves burner_onto_tank burner) (attaches-to burner_onto_tank fuel_tank) (excludes burner_onto_tank burner_onto_tank)
    ;; wick_into_burner: Thread the wick through the burner into the fuel.
    (available wick_into_burner) (insert-fit wick_into_burner) (moves wick_into_burner wick) (attaches-to wick_into_burner burner) (excludes wick_into_burner wick_into_burner)
    ;; lighter_lights_wick: Light the wick with the lighter.
    (available lighter_lights_wick) (ignite-fit lighter_lights_wick) (moves lighter_lights_wick lighter) (attaches-to lighter_lights_wick wick) (excludes lighter_lights_wick lighter_lights_wick)
    ;; chimney_onto_burner: Place the glass chimney on the burner.
    (available chimney_onto_burner) (place-fit chimney_onto_burner) (moves chimney_onto_burner glass_chimney) (attaches-to chimney_onto_burner burner) (excludes chimney_onto_burner lighter_lights_wick) (excludes chimney_onto_burner chimney_onto_burner)
  )
  (:goal (n-light)) ; light
)
