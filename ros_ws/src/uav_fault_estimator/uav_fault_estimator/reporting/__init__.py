"""A flight's report from its recording alone: metrics.json's figures of merit, the table
and the figures; and the calibration commands' files (calibration_output)."""
