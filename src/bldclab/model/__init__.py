"""The drive model.

The drive and its parts (:mod:`.motor`), the back-EMF shapes and cogging (:mod:`.emf`), the motor-file machinery
(:mod:`.motorfile`), units (:mod:`.units`), the shipped catalog (:mod:`.catalog`), paper 1's closed forms
(:mod:`.analytic`, one submodule per section of the paper) and controller gain design (:mod:`.design`).

Layer 1 of the package (see the developer guide's design page): imports only the base layer (errors, files).
"""
