(define (problem flashlight-n-light)
  (:domain causalplan-flashlight)
  (:objects batteries_into_bay head_onto_case - fit)
  (:init
    (in-assembly case)
    ;; batteries_into_bay: Insert the batteries into the case.
    (available batteries_into_bay) (insert-fit batteries_into_bay) (moves batteries_into_bay batteries) (attaches-to batteries_into_bay case) (excludes batteries_into_bay batteries_into_bay)
    ;; head_onto_case: Screw the head onto the case.
    (available head_onto_case) (screw-fit head_onto_case) (moves head_onto_case head) (attaches-to head_onto_case case) (excludes head_onto_case batteries_into_bay) (excludes head_onto_case head_onto_case)
  )
  (:goal (n-light)) ; light
)
