"""Decoding force direction from spikes: PSP features, linear SVM, cross-validation.

Shared by the offline analyses (``skinhil reproduce``) and the online receiver
(``skinhil train`` / ``listen``): one feature definition (:class:`FeatureSpec`), one
classifier (:class:`DirectionDecoder`) with a plain-data file format, one evaluation
(:func:`cross_validate`).
"""

from skinhil.decoding.classifier import DirectionDecoder
from skinhil.decoding.evaluate import CVResult, cross_validate
from skinhil.decoding.features import FeatureSpec
from skinhil.decoding.model_file import FORMAT_VERSION

__all__ = ["CVResult", "DirectionDecoder", "FORMAT_VERSION", "FeatureSpec", "cross_validate"]
