(define (problem desk_lamp-n-light)
  (:domain causalplan-desk_lamp)
  (:objects bulb_into_socket shade_onto_ring - fit)
  (:init
    (in-assembly base_with_cables)
    ;; bulb_into_socket: Screw the light bulb into the base with cables.
    (available bulb_into_socket) (screw-fit bulb_into_socket) (moves bulb_into_socket light_bulb) (attaches-to bulb_into_socket base_with_cables) (excludes bulb_into_socket bulb_into_socket)
    ;; shade_onto_ring: Clip the shade onto the base with cables.
    (available shade_onto_ring) (clip-fit shade_onto_ring) (moves shade_onto_ring shade) (attaches-to shade_onto_ring base_with_cables) (excludes shade_onto_ring bulb_into_socket) (excludes shade_onto_ring shade_onto_ring)
  )
  (:goal (n-light)) ; light
)
