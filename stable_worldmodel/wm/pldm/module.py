"""PLDM's building blocks: the same modules as LeWM's (upstream ships one copy per model)."""

from ..lewm.module import MLP, Attention, Block, ConditionalBlock, Embedder, FeedForward, Predictor, Transformer

__all__ = ["MLP", "Attention", "Block", "ConditionalBlock", "Embedder", "FeedForward", "Predictor", "Transformer"]
