"""The asset bank: asset records, procedural and cut-out assets, recolouring, rendering and the look check."""
