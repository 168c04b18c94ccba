"""The drive model.

The motor, motor, back-EMF shapes and motor files (:mod:`.motor`), units (:mod:`.units`), the shipped catalog
(:mod:`.catalog`), paper 1's closed forms (:mod:`.analytic`) and controller gain design (:mod:`.design`).

Layer 1 of the package (see the developer guide's design page): imports only the base layer (errors, files).
"""
