"""Appearance: skin tone, brows, lips, hair and stubble painted in UV space, and identities
that pair a shape preset with an appearance."""

from emogen.appearance.params import Appearance, appearance_from_dict

__all__ = ["Appearance", "appearance_from_dict"]
