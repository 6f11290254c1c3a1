"""Tuning: Optuna studies that search a gait's settings for the fastest walk that holds across the robustness
family (:mod:`.study`, :mod:`.space`, :mod:`.executor`), for op2motion's walk and for the stock firmware's."""
