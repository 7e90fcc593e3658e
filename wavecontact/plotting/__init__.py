"""Figures: matplotlib drawings of results and studies (Agg backend, nothing numerical imports this)."""
