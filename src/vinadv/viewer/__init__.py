"""Browser viewer and annotation tool for stored map pairs (`vinadv serve`).

`vinadv.viewer.app.create_app(store)` builds the Flask app (the `viewer` extra); `vinadv.viewer.label_set`
turns people's annotations into a training set for `vinadv classify train --labels human` and needs no Flask.
"""
