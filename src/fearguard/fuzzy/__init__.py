"""Fuzzy fear inference: rule files, the compiled engine, the scikit-fuzzy reference, and checks."""
