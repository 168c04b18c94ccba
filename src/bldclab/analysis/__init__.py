"""Analyses built on the simulator.

Analyses built on the simulator: steady-state experiments, paper 1 and paper 2 studies, the supply comparison, fault
injection and back-EMF identification.

Layer 5 of the package (see the developer guide's design page): imports model, control and sim, never sweep,
report or cli.
"""
