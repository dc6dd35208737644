"""Stage 3, hemi-cube form factors: the functions you write, gathered for the kit to call.

The kit imports this package and calls only the names below (see
``cs451/stages/hemicube/__init__.py`` for the interface and ``cs451/formfactors/``
for the engine that renders hemicubes with them). Keep them.
"""
from .contour import point_polygon_form_factor
from .itembuffer import form_factor_row, item_buffer_shaders
from .tables import delta_form_factors
from .tetrahedron import tetrahedron_delta_form_factors
from .views import hemicube_projections, hemicube_views

__all__ = ["delta_form_factors", "hemicube_views", "hemicube_projections", "item_buffer_shaders",
           "form_factor_row", "point_polygon_form_factor",
           "tetrahedron_delta_form_factors"]
