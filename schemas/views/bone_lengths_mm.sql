-- bone_lengths with length, uncertainty and residual in millimetres (units = 'mm').
CREATE OR REPLACE VIEW bone_lengths_mm AS
SELECT * REPLACE (
    length * mm_per_unit(units) AS length,
    uncertainty * mm_per_unit(units) AS uncertainty,
    residual * mm_per_unit(units) AS residual,
    'mm' AS units)
FROM bone_lengths;
