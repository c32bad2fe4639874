"""One-obstacle attacks: strategies that turn maps into (original, adversarial) map pairs."""
